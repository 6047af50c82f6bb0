"""Real renders: babbling calibration against the segmentation, and a tiny training run."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

try:
    from devlearn.infant import build_infant
except ImportError:  # the body is built in parallel; until it lands these tests skip
    build_infant = None

from devlearn_hand_regard.babbling import babble
from devlearn_hand_regard.calibration import calibrate
from devlearn_hand_regard.detector import HandDetector

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(build_infant is None, reason="devlearn.infant has not landed"),
]
CALIBRATION_STEPS = 1500  # the paper babbles 10,000 steps; 1,500 keep this test ~30 s


class SegmentationRecorder:
    """Wraps an infant; records the segmentation render whenever the eyes are read."""

    def __init__(self, infant) -> None:
        self.infant, self.segmentation = infant, []

    def __getattr__(self, name):
        return getattr(self.infant, name)

    def eyes(self):
        self.segmentation.append(self.infant.eyes_segmentation().copy())
        return self.infant.eyes()


@pytest.fixture(scope="module")
def real():
    """A calibration from real babbling, and 300 fresh babbling steps with segmentation."""
    infant = build_infant("sitting", senses=("proprioception", "eyes"))
    try:
        params = calibrate(babble(CALIBRATION_STEPS, seed=0, infant=infant))
        recorder = SegmentationRecorder(infant)
        held_out = babble(300, seed=1, infant=recorder)
        yield params, held_out, np.stack(recorder.segmentation), infant.hand_labels
    finally:
        infant.close()


def test_babbling_finds_arm_correlated_tracks(real):
    params = real[0]
    report = params.calibration
    assert report["hand_tracks"] >= 1 and min(report["rho_hand_tracks"]) > 0.6


def test_detector_finds_hands_where_segmentation_says_and_ignores_toys(real):
    from devlearn.infant.scenes import TOY_COLOURS
    from devlearn.infant.vision import BODY, SCENE

    params, data, segmentation, labels = real
    detector = HandDetector(params)
    for rgba in TOY_COLOURS:  # no toy block colour passes the learned colour test
        patch = np.full((4, 4, 3), np.array(rgba[:3]) * 255, np.uint8)
        assert not detector.colour_mask(patch).any()
    hand_ids = list(labels.values())
    found = visible = 0
    detected_labels = np.zeros(5)
    for t in range(len(data)):
        detections, masks = detector.detect(data.eyes[t])
        for eye in range(2):
            detected_labels += np.bincount(segmentation[t, eye][masks[eye].any(0)], minlength=5)
            if np.isin(segmentation[t, eye], hand_ids).sum() >= 20:  # a clearly visible hand
                visible += 1
                found += detections[eye].any()
    share = detected_labels / max(detected_labels.sum(), 1)
    # Detected pixels are the infant (hands, arms, some leg), never the toys or the floor.
    assert share[SCENE] < 0.05
    assert share[hand_ids].sum() + share[BODY] > 0.95
    assert visible > 0 and found / visible >= 0.5


def test_tiny_training_run_and_eval(tmp_path, real):
    out = tmp_path / "run"
    out.mkdir()
    real[0].save(out / "hand_detector.json")  # prepare() reuses it: no 10,000-step babbling
    cmd = [sys.executable, "-m", "devlearn.cli", "run", "hand_regard", "--steps", "256",
           "--envs", "2", "--seed", "1", "--out", str(out),
           "--set", "behavior.left_arm_steps=128", "--set", "behavior.right_arm_steps=64"]
    subprocess.run(cmd, check=True, timeout=600)
    rows = [json.loads(line) for line in (out / "metrics.jsonl").read_text().splitlines()]
    # Episodes last 1,000 steps, so none ends here (per-term sums appear at episode ends).
    assert rows[-1]["step"] >= 256 and np.isfinite(rows[-1]["mean_step_reward"])
    assert [r["stage"] for r in rows] == ["left_arm", "right_arm"]
    config = json.loads((out / "config.json").read_text())
    assert config["behavior"]["detector_file"].endswith("hand_detector.json")
    evaluation = tmp_path / "eval"
    cmd = [sys.executable, "-m", "devlearn.cli", "eval", "hand_regard", "--checkpoint",
           str(out / "checkpoint_latest.pt"), "--episodes", "1", "--out", str(evaluation)]
    subprocess.run(cmd, check=True, timeout=600)
    summary = json.loads((evaluation / "eval.json").read_text())
    assert summary["episodes"] == 1 and summary["steps"] == 1000
    assert set(summary["visibility"]) == {"left_eye_left_hand", "right_eye_left_hand",
                                          "left_eye_right_hand", "right_eye_right_hand"}
    assert 0.0 <= summary["average"] <= 1.0 and "detector_agreement" in summary
    assert (evaluation / "hand_regard_visibility.png").stat().st_size > 0
