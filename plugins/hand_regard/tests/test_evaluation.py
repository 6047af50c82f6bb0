"""Visibility metrics, the detector's agreement with ground truth, and the bar chart."""

from __future__ import annotations

import json

import numpy as np
import pytest
from devlearn_hand_regard import HandRegard
from devlearn_hand_regard.evaluation import HandRegardEvaluator

from devlearn.api.rewards import StepContext


class Truth:
    """A stand-in infant whose ground-truth verdicts (criterion -> (2, 2) bool) are set per step."""

    verdicts: dict = {}


def scripted(infant):
    return infant.verdicts


def step(evaluator, truth, detected, cone=None):
    infant = Truth()
    truth = np.asarray(truth, bool)
    infant.verdicts = {
        "pixels": truth,
        "babybench": np.zeros((2, 2), bool),
        "cone": truth if cone is None else np.asarray(cone, bool),
        "any_pixel": truth,
    }
    facts = {"hand_detections": np.asarray(detected, bool)}
    evaluator.record(StepContext(infant, {}, facts, 0, False, {}))


def test_eval_mode_visibility_and_agreement(tmp_path):
    evaluator = HandRegardEvaluator(ground_truth=True, measure=scripted)
    # Left hand seen by both eyes on all 4 steps; right hand by the right eye on 1 step.
    # The detector misses the left hand in the right eye once and fires falsely once.
    step(evaluator, [[1, 0], [1, 1]], [[1, 0], [1, 1]])
    step(evaluator, [[1, 0], [1, 0]], [[1, 0], [0, 0]])
    step(evaluator, [[1, 0], [1, 0]], [[1, 1], [1, 0]])
    step(evaluator, [[1, 0], [1, 0]], [[1, 0], [1, 0]])
    metrics = evaluator.end_episode()
    assert metrics == pytest.approx(
        {
            "left_eye_left_hand": 1.0,  # the detector's own detections: the headline
            "right_eye_left_hand": 0.75,
            "left_eye_right_hand": 0.25,
            "right_eye_right_hand": 0.25,
            "average": 0.5625,
            "average_pixels": 0.5625,
            "average_babybench": 0.0,
            "average_cone": 0.5625,
            "average_any_pixel": 0.5625,
        }
    )
    summary = json.loads(json.dumps(evaluator.summary()))
    assert summary["episodes"] == 1 and summary["steps"] == 4
    assert summary["average"] == pytest.approx(0.5625)
    assert summary["visibility_source"] == "scene" and summary["headline_criterion"] == "detector"
    assert list(summary["criteria"]) == ["detector", "pixels", "babybench", "cone", "any_pixel"]
    assert summary["detector_visibility"]["left_eye_right_hand"] == pytest.approx(0.25)
    assert summary["criteria"]["detector"]["visibility"]["left_eye_right_hand"] == 0.25
    agreement = summary["detector_agreement"]
    assert agreement["right_eye_left_hand"] == pytest.approx(
        {"accuracy": 0.75, "precision": 1.0, "recall": 0.75}
    )
    assert agreement["left_eye_right_hand"] == {"accuracy": 0.75, "precision": 0.0, "recall": None}
    # averages over the pairs that have a value: precision 1, 1, 0, 1; recall 1, 0.75, 1
    assert agreement["average"] == pytest.approx(
        {"accuracy": 0.875, "precision": 0.75, "recall": 2.75 / 3}
    )
    assert evaluator.protocol()["detector_truth"] == "pixels"
    paths = evaluator.write_artifacts(tmp_path)
    assert paths == [tmp_path / "hand_regard_visibility.png"]
    assert paths[0].read_bytes()[:4] == b"\x89PNG"


class Rendered(Truth):
    """A stand-in infant with a segmentation (left hand label 1, right hand 2)."""

    hand_labels = {"left": 1, "right": 2}

    def __init__(self, segmentation) -> None:
        self.segmentation = segmentation

    def eyes_segmentation(self):
        return self.segmentation


def test_eval_reports_pixel_precision_and_recall_per_hand():
    evaluator = HandRegardEvaluator(ground_truth=True, measure=scripted)
    seg = np.zeros((2, 4, 4), np.int32)
    seg[0, 0, :4] = 1  # left hand: 4 pixels in the left eye, 2 in the right
    seg[1, 0, :2] = 1
    seg[1, 3, :3] = 3  # body
    masks = np.zeros((2, 2, 4, 4), bool)
    masks[0, 0, 0, :2] = True  # 2 left-hand pixels found in the left eye ...
    masks[1, 0, 0, :2] = True  # ... 2 in the right eye
    masks[1, 0, 3, :3] = True  # and 3 body pixels called the left hand
    masks[1, 1, 3, :1] = True  # 1 body pixel called the right hand
    infant = Rendered(seg)
    infant.verdicts = {k: np.array([[1, 0], [1, 0]], bool) for k in ("cone", "pixels")}
    facts = {"hand_detections": masks.any(axis=(2, 3)), "hand_masks": masks}
    evaluator.record(StepContext(infant, {}, facts, 0, False, {}))
    pixels = evaluator.summary()["detector_pixels"]
    assert pixels["left_hand"] == pytest.approx({"precision": 4 / 7, "recall": 4 / 6})
    assert pixels["right_hand"] == {"precision": 0.0, "recall": None}


def test_training_mode_uses_the_detector():
    evaluator = HandRegard().evaluation().evaluator(True)
    step(evaluator, [[0, 0], [0, 0]], [[1, 1], [0, 0]])  # truth ignored in training
    step(evaluator, [[0, 0], [0, 0]], [[1, 0], [0, 0]])
    metrics = evaluator.end_episode()
    assert metrics["left_eye_left_hand"] == 1.0 and metrics["left_eye_right_hand"] == 0.5
    assert metrics["average"] == pytest.approx(0.375)
    assert "detector_agreement" not in evaluator.summary()
    assert evaluator.end_episode() == {}  # nothing recorded since


def test_headline_is_the_detector_and_episodes_have_a_spread():
    evaluator = HandRegardEvaluator(ground_truth=True, measure=scripted)
    # Episode 1: the left hand in both eyes; the detector finds it in the left eye once.
    step(evaluator, [[1, 0], [1, 0]], [[1, 0], [0, 0]], cone=[[1, 0], [0, 0]])
    step(evaluator, [[1, 0], [1, 0]], [[0, 0], [0, 0]], cone=[[0, 0], [0, 0]])
    first = evaluator.end_episode()
    # Episode 2: nothing in view.
    step(evaluator, [[0, 0], [0, 0]], [[0, 0], [0, 0]])
    evaluator.end_episode()
    assert first["average"] == pytest.approx(0.125) and first["average_any_pixel"] == 0.5
    assert first["average_cone"] == pytest.approx(0.125)
    summary = evaluator.summary()
    assert summary["average"] == pytest.approx(1 / 12)  # 1 detection of 3 steps, 4 pairs
    assert summary["criteria"]["any_pixel"]["average"] == pytest.approx(2 * 2 / 12)
    assert summary["episode_average_mean"] == pytest.approx(0.0625)
    from scipy import stats

    low, high = stats.t.interval(0.95, 1, loc=0.0625, scale=stats.sem([0.125, 0.0]))
    assert summary["episode_average_ci_low"] == pytest.approx(low)
    assert summary["episode_average_ci_high"] == pytest.approx(high)
    assert evaluator.protocol()["criteria"]["pixels"]["min_pixels"] == 20
