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
  hand before both eyes; the position rule credits it to the right in the left eye on 96%.

The contingency rule, with the committed detector of ``results/hand_regard/i58_attribution``,
credits no absent hand on either (at most 1% of steps), and still credits the hand in view
on the second (a rule that credits nothing would fail that).
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
    ("reach_t4_seed2_episode1.npz", "visibility", 0.0),
    ("i29_bilateral_seed2_episode1.npz", "position", 0.3),
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


def test_contingency_needs_a_detector_with_its_model(params):
    without = DetectorParams(**{**params.__dict__, "contingency_model": {}})
    with pytest.raises(ValueError, match="contingency_model"):
        HandDetector(without, attribution="contingency")
