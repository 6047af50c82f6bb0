"""Calibration on synthetic babbling, the detector, its JSON file and the hand optical flow."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from devlearn_hand_regard.calibration import CalibrationError, calibrate
from devlearn_hand_regard.detector import DetectorParams, HandDetector, HandFlow
from devlearn_hand_regard.hand_colour import hsv_boxes
from synthetic import BLOCKS, MAGENTA, SKIN, draw, synthetic_babbling

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


def test_posture_model_tells_crossed_hands_apart(synthetic_params):
    """Hand positions linear in the joint angles: the learned model predicts them, and a blob
    on the 'wrong' side of the mean positions is still attributed by the posture."""
    from devlearn_hand_regard.calibration import Track, position_model

    rng = np.random.default_rng(0)
    steps, n_joints = 400, 4
    angles = rng.uniform(-1, 1, (steps, n_joints))
    proprioception = np.c_[angles, np.zeros((steps, 5 * n_joints))]

    def where(side, q):  # left hand follows joint 0, right hand joint 1; both swing widely
        return np.array([32 + 20 * q[side], 40 + 5 * q[2 + side]])

    hands = []
    for side in range(2):
        for eye in range(2):
            track = Track(eye, 0, side=side)
            track.steps = list(range(eye, steps, 2))
            track.centroids = [tuple(where(side, angles[s]) + [eye, 0]) for s in track.steps]
            hands.append(track)
    model = position_model(hands, proprioception, ridge=0.1)
    detector = HandDetector(DetectorParams(**{**vars(synthetic_params), "position_model": model}))
    crossed = np.array([0.8, -0.8, 0.0, 0.0])  # left hand at x ~ 48, right hand at x ~ 16
    p = np.r_[crossed, np.zeros(5 * n_joints)]
    np.testing.assert_allclose(detector.expected_positions(0, p), [[48, 40], [16, 40]], atol=1.0)
    frame = draw(np.array([[48.0, 40.0], [np.nan, np.nan]]), BLOCK_POSITIONS)
    eyes = np.stack([frame, frame])
    assert detector.detect(eyes, p)[0].tolist() == [[True, False], [True, False]]
    # Without proprioception the mean positions decide: x = 48 is the right hand's side.
    assert detector.detect(eyes)[0].tolist() == [[False, True], [False, True]]


def test_a_hand_predicted_outside_the_image_is_never_chosen(synthetic_params, monkeypatch):
    """The posture puts the right hand outside the image: a blob near where it would be is
    not called the right hand; the left hand takes it only when predicted inside."""
    detector = HandDetector(synthetic_params)
    frame = draw(np.array([[56.0, 40.0], [np.nan, np.nan]]), BLOCK_POSITIONS)
    eyes = np.stack([frame, frame])
    cases = {
        "right outside": ([[20.0, 40.0], [80.0, 40.0]], [True, False]),  # nearer right, but out
        "left outside": ([[-9.0, 40.0], [40.0, 40.0]], [False, True]),
        "both outside": ([[20.0, -5.0], [70.0, 40.0]], [False, False]),
        "both inside": ([[20.0, 40.0], [60.0, 40.0]], [False, True]),  # the nearer one
    }
    for name, (expected, seen) in cases.items():
        monkeypatch.setattr(detector, "expected_positions", lambda eye, p, e=expected: np.array(e))
        assert detector.detect(eyes, np.zeros(4))[0].tolist() == [seen, seen], name
    # Two blobs, one hand predicted outside: only one is attributed, to the hand inside.
    frame = draw(np.array([[20.0, 40.0], [46.0, 42.0]]), BLOCK_POSITIONS)
    monkeypatch.setattr(
        detector, "expected_positions", lambda eye, p: np.array([[22, 40], [70, 40]])
    )
    detections, masks = detector.detect(np.stack([frame, frame]), np.zeros(4))
    assert detections.tolist() == [[True, False], [True, False]]
    ys, xs = np.nonzero(masks[0, 0])
    assert abs(xs.mean() - 20) < 2


def test_posture_model_is_kept_only_when_it_predicts_unseen_tracks():
    """Validated on every other track: a posture-driven hand keeps its model; hands whose
    image positions do not follow the posture (noise) fall back to the mean positions."""
    from devlearn_hand_regard.calibration import Track, position_model

    rng = np.random.default_rng(1)
    steps, n_joints = 600, 4
    angles = rng.uniform(-1, 1, (steps, n_joints))
    proprioception = np.c_[angles, np.zeros((steps, 5 * n_joints))]

    def tracks(where):
        out = []
        for side in range(2):
            for k in range(6):  # six tracks per arm, 50 steps each
                track = Track(k % 2, 0, side=side)
                track.steps = list(range(side * 300 + 50 * k, side * 300 + 50 * (k + 1)))
                track.centroids = [tuple(where(side, s)) for s in track.steps]
                out.append(track)
        return out

    linear = tracks(lambda side, s: [32 + 20 * angles[s, side], 40 + 5 * angles[s, 2 + side]])
    model = position_model(linear, proprioception, ridge=0.1, max_error=16.0)
    assert model and model["validation_error_px"] < 2.0
    noise = tracks(lambda side, s: rng.uniform(0, 64, 2))
    assert position_model(noise, proprioception, ridge=0.1, max_error=16.0) == {}
    assert position_model(noise, proprioception, ridge=0.1)  # unvalidated: kept, as before
    episode = np.arange(steps) // 100  # folds by babbling episode, as calibrate() asks
    kept = position_model(linear, proprioception, ridge=0.1, max_error=16.0, episode=episode)
    assert kept and kept["validation_error_px"] < 2.0
    assert position_model(noise, proprioception, 0.1, max_error=16.0, episode=episode) == {}


def test_a_still_arm_jostled_in_rhythm_does_not_claim_the_moving_hand(monkeypatch):
    """One arm babbles per episode while the other turns at 1% of its speed in the same
    rhythm: correlation ignores scale, so before issue #29's rule (candidates must move) the
    still arm claimed many of the moving hand's tracks."""
    import devlearn_hand_regard.calibration as calibration

    data = synthetic_babbling(3000, seed=0, alternate=500)
    seen = {}

    def keep(hands, *args, **kwargs):
        seen["hands"] = hands
        return {}

    monkeypatch.setattr(calibration, "position_model", keep)
    calibrate(data)
    hands = seen["hands"]
    assert len(hands) >= 4
    wrong = [t for t in hands if t.side != data.episode[t.steps[0]] % 2]
    assert not wrong, [(t.side, int(data.episode[t.steps[0]])) for t in wrong]


def test_two_coloured_hands_are_told_apart_by_colour_wherever_they_are():
    """Hands of two colours, babbling one arm at a time: calibration learns each hand's own
    colour, and the detector attributes by colour, even with the hands crossed (positions
    would swap them)."""
    colours = (SKIN, MAGENTA)
    data = synthetic_babbling(3000, seed=0, colours=colours, alternate=500)
    params = calibrate(data, per_hand_colours=True)
    assert params.calibration["hands_told_by_colour"]
    assert inside(params.side_hsv_ranges[0], hsv(SKIN))
    assert not inside(params.side_hsv_ranges[0], hsv(MAGENTA))
    assert inside(params.side_hsv_ranges[1], hsv(MAGENTA))
    assert not inside(params.side_hsv_ranges[1], hsv(SKIN))
    detector = HandDetector(params)
    crossed = draw(np.array([[50.0, 40.0], [14.0, 40.0]]), BLOCK_POSITIONS, colours=colours)
    detections, masks = detector.detect(np.stack([crossed, crossed]))
    assert detections.all()
    assert np.nonzero(masks[0, 0])[1].mean() > 40  # the left hand, on the right
    only_left = draw(np.array([[40.0, 40.0], [np.nan, np.nan]]), BLOCK_POSITIONS, colours=colours)
    detections, _ = detector.detect(np.stack([only_left, only_left]))
    np.testing.assert_array_equal(detections, [[True, False], [True, False]])


def test_one_colour_for_both_hands_keeps_attribution_by_position(synthetic_params):
    assert synthetic_params.side_hsv_ranges == []
    assert synthetic_params.calibration["hands_told_by_colour"] is False


def test_in_a_one_arm_stage_a_blob_is_the_moving_arms_hand(synthetic_params):
    """With the right arm switched off (hanging out of view), a blob where the left hand
    usually is still is the left hand; with the left arm off, the same blob is the right
    hand: position would have said left."""
    detector = HandDetector(synthetic_params)
    frame = draw(np.array([[20.0, 40.0], [np.nan, np.nan]]), BLOCK_POSITIONS)
    eyes = np.stack([frame, frame])
    np.testing.assert_array_equal(detector.detect(eyes)[0], [[True, False], [True, False]])
    np.testing.assert_array_equal(detector.detect(eyes, hands=[0])[0], [[True, False]] * 2)
    np.testing.assert_array_equal(detector.detect(eyes, hands=[1])[0], [[False, True]] * 2)
    both = draw(np.array([[20.0, 40.0], [44.0, 40.0]]), BLOCK_POSITIONS)
    detections, masks = detector.detect(np.stack([both, both]), hands=[1])
    np.testing.assert_array_equal(detections, [[False, True]] * 2)
