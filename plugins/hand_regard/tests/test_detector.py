"""Calibration on synthetic babbling, the detector, its JSON file and the hand optical flow."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from devlearn_hand_regard.calibration import CalibrationError, calibrate
from devlearn_hand_regard.detector import DetectorParams, HandDetector, HandFlow
from devlearn_hand_regard.hand_colour import hsv_boxes
from synthetic import BLOCKS, SKIN, draw, synthetic_babbling

BLOCK_POSITIONS = np.array([[12.0, 52.0], [32.0, 56.0], [52.0, 50.0]])


def hsv(rgb) -> np.ndarray:
    return cv2.cvtColor(np.array([[rgb]], np.uint8), cv2.COLOR_RGB2HSV)[0, 0]


def inside(boxes, colour) -> bool:
    return any(np.all(colour >= b[:3]) and np.all(colour <= b[3:]) for b in boxes)


def test_babbling_discovers_the_hands_not_the_blocks(synthetic_params):
    report = synthetic_params.calibration
    assert report["hand_tracks"] >= 2 and min(report["rho_hand_tracks"]) > 0.6
    assert inside(synthetic_params.hsv_ranges, hsv(SKIN))
    for block in BLOCKS:
        assert not inside(synthetic_params.hsv_ranges, hsv(block))
    # Disc of radius 5: about 81 pixels.
    assert 60 <= synthetic_params.expected_area <= 100
    # Both arms were found, each in both eyes.
    assert all(n > 0 for n in report["hand_frames"].values())


def test_detector_finds_and_attributes_both_hands(synthetic_params):
    detector = HandDetector(synthetic_params)
    frame = draw(np.array([[24.0, 38.0], [46.0, 42.0]]), BLOCK_POSITIONS)
    detections, masks = detector.detect(np.stack([frame, frame]))
    assert detections.all()
    for hand, (x, y) in enumerate([(24, 38), (46, 42)]):
        ys, xs = np.nonzero(masks[0, hand])
        assert abs(xs.mean() - x) < 1.0 and abs(ys.mean() - y) < 1.0
    only_right = draw(np.array([[np.nan, np.nan], [46.0, 42.0]]), BLOCK_POSITIONS)
    detections, _ = detector.detect(np.stack([only_right, frame]))
    np.testing.assert_array_equal(detections, [[False, True], [True, True]])
    nothing = draw(np.full((2, 2), np.nan), BLOCK_POSITIONS)
    assert not detector.detect(np.stack([nothing, nothing]))[0].any()


def test_uncalibrated_detector_sees_nothing():
    frame = draw(np.array([[24.0, 38.0], [46.0, 42.0]]), BLOCK_POSITIONS)
    assert not HandDetector(None).detect(np.stack([frame, frame]))[0].any()


def test_params_round_trip_through_json(tmp_path, synthetic_params):
    path = synthetic_params.save(tmp_path / "d.json")
    loaded = DetectorParams.load(path)
    assert loaded == synthetic_params


def test_calibration_fails_clearly_without_moving_hands():
    data = synthetic_babbling(200, seed=1)
    data.arm_speed[:] = np.random.default_rng(0).uniform(size=data.arm_speed.shape)
    with pytest.raises(CalibrationError, match="no blob track correlated"):
        calibrate(data)


def test_hsv_boxes_split_around_the_red_wrap():
    pixels = np.array([[175, 200, 200], [178, 210, 190], [2, 205, 210], [4, 190, 200]] * 10)
    boxes = hsv_boxes(pixels, 0, 100, margin=(0, 0, 0))
    hues = sorted((b[0], b[3]) for b in boxes)
    assert hues == [(0, 4), (175, 179)]


def test_flow_measures_the_hands_motion(synthetic_params):
    detector, flow = HandDetector(synthetic_params), HandFlow()
    blocks = BLOCK_POSITIONS
    first = draw(np.array([[24.0, 38.0], [46.0, 42.0]]), blocks)
    second = draw(np.array([[26.0, 38.0], [46.0, 42.0]]), blocks)  # left hand moves 2 px
    for frame, moving in ((first, False), (second, True)):
        eyes = np.stack([frame, frame])
        _, masks = detector.detect(eyes)
        total, pixels = flow.update(eyes, masks)
        if not moving:
            assert pixels.sum() == 0  # no previous frame: nothing measured
    left = total[0, 0] / pixels[0, 0]
    right = total[0, 1] / pixels[0, 1]
    assert 1.0 < left < 3.0 and right < 0.3
    flow.reset()
    assert flow.previous is None
