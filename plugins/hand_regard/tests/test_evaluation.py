"""Visibility metrics, the detector's agreement with ground truth, and the bar chart."""

from __future__ import annotations

import json

import numpy as np
import pytest
from devlearn_hand_regard import HandRegard

from devlearn.rewards import StepContext


class Truth:
    """A stand-in infant whose ground-truth visibility is set per step."""

    visibility = np.zeros((2, 2), bool)

    def hand_visibility(self):
        return self.visibility


def step(evaluator, truth, detected):
    infant = Truth()
    infant.visibility = np.asarray(truth, bool)
    facts = {"hand_detections": np.asarray(detected, bool)}
    evaluator.record(StepContext(infant, {}, facts, 0, False, {}))


def test_eval_mode_visibility_and_agreement(tmp_path):
    evaluator = HandRegard().evaluator(training=False)
    # Left hand seen by both eyes on all 4 steps; right hand by the right eye on 1 step.
    # The detector misses the left hand in the right eye once and fires falsely once.
    step(evaluator, [[1, 0], [1, 1]], [[1, 0], [1, 1]])
    step(evaluator, [[1, 0], [1, 0]], [[1, 0], [0, 0]])
    step(evaluator, [[1, 0], [1, 0]], [[1, 1], [1, 0]])
    step(evaluator, [[1, 0], [1, 0]], [[1, 0], [1, 0]])
    metrics = evaluator.end_episode()
    assert metrics == pytest.approx({
        "left_eye_left_hand": 1.0, "right_eye_left_hand": 1.0, "left_eye_right_hand": 0.0,
        "right_eye_right_hand": 0.25, "average": 0.5625})
    summary = json.loads(json.dumps(evaluator.summary()))
    assert summary["episodes"] == 1 and summary["steps"] == 4
    assert summary["average"] == pytest.approx(0.5625)
    assert summary["visibility_source"] == "segmentation"
    assert summary["detector_visibility"]["left_eye_right_hand"] == pytest.approx(0.25)
    agreement = summary["detector_agreement"]
    assert agreement["right_eye_left_hand"] == pytest.approx(
        {"accuracy": 0.75, "precision": 1.0, "recall": 0.75})
    assert agreement["left_eye_right_hand"] == {"accuracy": 0.75, "precision": 0.0,
                                                "recall": None}
    paths = evaluator.write_artifacts(tmp_path)
    assert paths == [tmp_path / "hand_regard_visibility.png"]
    assert paths[0].read_bytes()[:4] == b"\x89PNG"


def test_training_mode_uses_the_detector():
    evaluator = HandRegard().evaluator(training=True)
    step(evaluator, [[0, 0], [0, 0]], [[1, 1], [0, 0]])  # truth ignored in training
    step(evaluator, [[0, 0], [0, 0]], [[1, 0], [0, 0]])
    metrics = evaluator.end_episode()
    assert metrics["left_eye_left_hand"] == 1.0 and metrics["left_eye_right_hand"] == 0.5
    assert metrics["average"] == pytest.approx(0.375)
    assert "detector_agreement" not in evaluator.summary()
    assert evaluator.end_episode() == {}  # nothing recorded since
