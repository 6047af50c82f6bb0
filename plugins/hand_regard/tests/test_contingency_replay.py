"""Issue #58 item 2: recorded fooling episodes replayed through the side attributions.

Each data file is one evaluation episode (1,000 steps from BabyBench's start, 201 decisions)
of a published policy that fooled the rule it trained with, reduced to a blob table
(:mod:`devlearn_hand_regard.blob_table`: the colour detector's blobs, the proprioception and
the segmentation's hand pixels; recorded with ``python -m
devlearn_hand_regard.contingency_check replay ... --tables DIR``, episode 1 of 10):

- ``reach_t4_seed2_episode1.npz``: issue #39's ``reward=reach_t4,seed=2``: the left hand
  before both eyes, the right hand in neither; the visibility rule credits the right hand
  in the right eye on 94% of steps;
- ``i29_bilateral_seed2_episode1.npz``: issue #29's ``reward=bilateral,seed=2``: the left
  hand before both eyes; the position rule credits it to the right in the left eye on 96%;
- ``reach_t4_seed1_episode1.npz``: issue #39's ``reward=reach_t4,seed=1``: the left hand
  low in the right eye's corner, the right arm hanging just below the view; the visibility
  rule credits the absent right hand on 91% of steps, and issue #58's first contingency rule
  (nearest babbled postures, results at 10096f0) on 24%.

- ``i58_pilot_both_seed3_episode4.npz``: issue #58's pilot, ``both_hands_contingency``
  seed 3 (trained under the contingency rule without blob pairs): both hands in view beside
  each other, two blobs, the other hand within the rule's margin of each.

The contingency rule, with the committed detector of ``results/hand_regard/i58_attribution``,
credits no absent hand on any (at most 1% of steps), and still credits the hand in view
(a rule that credits nothing would fail that).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from devlearn_hand_regard.blob_table import BlobTable
from devlearn_hand_regard.contingency_check import credits, score_credits
from devlearn_hand_regard.detector import DetectorParams, HandDetector

DATA = Path(__file__).parent / "data"
DETECTOR = (
    Path(__file__).resolve().parents[3]
    / "results/hand_regard/i58_attribution/contingency_detector.json"
)
EPISODES = [
    ("reach_t4_seed2_episode1.npz", "visibility", 0.5),
    ("i29_bilateral_seed2_episode1.npz", "position", 0.5),
    ("reach_t4_seed1_episode1.npz", "visibility", 0.15),
]
"""(file, the rule the policy trained with, the least recall the new rule must keep)."""
TARGET = 0.01
"""Issue #58: false credit on at most 1% of steps."""


@pytest.fixture(scope="module")
def params() -> DetectorParams:
    return DetectorParams.load(DETECTOR)


@pytest.mark.parametrize(("name", "old_rule", "least_recall"), EPISODES)
def test_the_old_rule_was_fooled_and_the_contingency_rule_is_not(
    params, name, old_rule, least_recall
):
    table = BlobTable.load(DATA / name)
    assert len(table) == 201
    old = score_credits(credits(HandDetector(params, attribution=old_rule), old_rule, table), table)
    assert old["false_credit"] > TARGET  # the recorded episode does fool the old rule
    new_detector = HandDetector(params, attribution="contingency")
    new = score_credits(credits(new_detector, "contingency", table), table)
    assert new["false_credit"] <= TARGET
    assert (new["recall"] or 0.0) >= least_recall


def test_two_blobs_beside_each_other_are_paired_without_false_credit(params):
    """Both hands in view side by side: without the pairing (the pilot's rule) the rule
    credits no side on many of these steps; paired, recall rises and no absent hand is
    credited."""
    table = BlobTable.load(DATA / "i58_pilot_both_seed3_episode4.npz")
    scored = {
        pairs: score_credits(
            credits(
                HandDetector(params, attribution="contingency", pair_blobs=pairs),
                "contingency",
                table,
            ),
            table,
        )
        for pairs in (False, True)
    }
    assert scored[False]["recall"] < 0.6
    assert scored[True]["recall"] > 0.75
    assert scored[True]["false_credit"] == 0.0


def test_contingency_needs_a_detector_with_its_model(params):
    without = DetectorParams(**{**params.__dict__, "contingency_model": {}})
    with pytest.raises(ValueError, match="contingency_model"):
        HandDetector(without, attribution="contingency")


def test_the_detector_detects_what_the_rule_credits(params, monkeypatch):
    """``HandDetector.detect`` under ``contingency``: the blobs its colour step finds (here
    the recorded episode's, each a small square mask) go through the rule once per decision;
    the detections and masks are the credited blobs', the same pairs as the offline
    replay, and :meth:`HandDetector.reset` starts the tracks anew."""
    import numpy as np
    from devlearn_hand_regard.detector import Blob

    table = BlobTable.load(DATA / "i29_bilateral_seed2_episode1.npz")
    detector = HandDetector(params, attribution="contingency")
    frame = {"t": 0, "eye": 0}

    def recorded_blobs(image, side=None):
        t, eye = frame["t"], frame["eye"]
        frame["eye"] = 1 - eye
        found = []
        for x, y, area in table.blobs[t, eye]:
            if np.isfinite(x):
                mask = np.zeros((64, 64), dtype=bool)
                mask[max(int(y) - 2, 0) : int(y) + 3, max(int(x) - 2, 0) : int(x) + 3] = True
                found.append(Blob((float(x), float(y)), float(area), mask))
        return found

    monkeypatch.setattr(detector, "blobs", recorded_blobs)
    eyes = np.zeros((2, 64, 64, 3), dtype=np.uint8)
    detector.reset()
    detected = np.zeros((len(table), 2, 2), dtype=bool)
    for t in range(len(table)):
        frame["t"] = t
        detected[t], masks = detector.detect(eyes, table.proprioception[t])
        assert (masks.any(axis=(2, 3)) == detected[t]).all()
    np.testing.assert_array_equal(detected, credits(detector, "contingency", table))
    assert detected[:, :, 0].mean() > 0.3 and not detected[:, :, 1].any()
