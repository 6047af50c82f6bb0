"""Babbling on the skin-tone infant (bare hands the body's colour, natural toy colours): what
the paper's method finds there, measured against the segmentation on random-start frames."""

from __future__ import annotations

import numpy as np
import pytest
from devlearn_hand_regard.babbling import babble
from devlearn_hand_regard.calibration import calibrate
from devlearn_hand_regard.detector import HandDetector
from devlearn_hand_regard.segmentation_score import held_out, score

from devlearn import build_infant

pytestmark = pytest.mark.slow
CALIBRATION_STEPS = 2500
"""Short babbling (the paper: 10,000) keeps this test ~20 s; at 2,500 steps the colour learned
is the lit skin's, as at 10,000 (results/hand_regard/README.md, "Detector, both
appearances"). Pixel precision is low at every length tried, which is what this test pins."""
TEST_EPISODES, TEST_EPISODE_STEPS = 2, 150
"""Random-start test frames (as ``devlearn eval`` starts), seed 1."""


@pytest.fixture(scope="module")
def skin():
    """A calibration from real babbling on the skin infant and its score on test frames."""
    with build_infant("sitting", senses=("proprioception", "eyes"), appearance="skin") as infant:
        # The scene and babbling of runs before issue #29, where the figures were measured.
        params = calibrate(babble(CALIBRATION_STEPS, seed=0, infant=infant, start="rest"))
        data, segmentation = held_out(
            infant,
            TEST_EPISODES * TEST_EPISODE_STEPS,
            seed=1,
            episode_steps=TEST_EPISODE_STEPS,
            random_pose=True,
            hold_steps=8,
        )
        yield params, score(HandDetector(params), data, segmentation)


def test_babbling_finds_arm_correlated_skin_coloured_tracks(skin):
    params = skin[0]
    report = params.calibration
    # Blob tracks moving with the arms are found (rho > 0.6), as with mittens ...
    assert report["hand_tracks"] >= 5 and min(report["rho_hand_tracks"]) > 0.6
    # ... and the colour learned from them includes the skin's (OpenCV hue 12).
    assert any(box[0] <= 12 <= box[3] for box in params.hsv_ranges), params.hsv_ranges


def test_skin_detector_finds_the_hands_but_not_only_them(skin):
    # What fails: the learned colour is also the body's, so the detector finds the hands
    # (recall) but most of what it marks is arm, leg and trunk (pixel precision). Measured at
    # these seeds: any hand in an eye recall 0.94 (precision 0.65: hands are in 42% of these
    # few frames); detected pixels 0.37 hands, 0.63 body; pixel precision per hand 0.18 and
    # 0.09; pair-averaged precision 0.34. Mittens: 0.999 of the detected pixels are hands.
    result = skin[1]
    assert result["any_hand"]["recall"] > 0.8
    assert result["pixels"]["body"] > 0.5
    assert result["pixels"]["left_hand"] + result["pixels"]["right_hand"] < 0.5
    assert all(p["precision"] < 0.3 for p in result["hand_pixels"].values())
    assert result["pair_mean"]["precision"] < 0.45


def test_skin_detector_fires_on_a_skin_coloured_forearm(skin):
    # A flat patch of the body's own skin colour is "hand" to the skin detector.
    from devlearn.testing import SKIN_RGBA

    patch = np.full((8, 8, 3), np.array(SKIN_RGBA[:3]) * 255 * 0.9, np.uint8)
    assert HandDetector(skin[0]).colour_mask(patch).mean() > 0.5


def test_babbling_shows_progress_and_starts_as_told(monkeypatch, capsys):
    """A line on stderr every PROGRESS_SECONDS (0 here: every step), in BabyBench's scene from
    its start, which the infant's reset is asked for."""
    from devlearn_hand_regard import babbling

    monkeypatch.setattr(babbling, "PROGRESS_SECONDS", 0.0)
    infant = build_infant("sitting_babybench", senses=("proprioception", "eyes"))
    starts = []
    reset = infant.reset
    monkeypatch.setattr(infant, "reset", lambda rng, **kw: (starts.append(kw), reset(rng, **kw))[1])
    try:
        data = babbling.babble(12, seed=0, infant=infant, episode_steps=6, progress=True)
    finally:
        infant.close()
    assert len(data) == 12 and starts == [{"start": "babybench"}] * 2
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) >= 5 and lines[-1].startswith("babbling: ") and "/ 12 steps" in lines[-1]
