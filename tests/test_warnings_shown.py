"""Warnings only where they matter: not from ``devlearn info`` or ``bench``'s env figure."""

from __future__ import annotations

import warnings

import pytest

from devlearn.bench.learner import bench_update
from devlearn.bench.speed import bench_behavior_env
from devlearn.evaluation.describe import describe_behavior

hand_regard = pytest.importorskip("devlearn_hand_regard")


def _warnings(call) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        call()
    return [str(w.message) for w in caught]


def test_info_and_bench_do_not_warn_about_the_uncalibrated_detector():
    assert _warnings(lambda: describe_behavior(hand_regard.HandRegard())) == []
    assert _warnings(lambda: bench_behavior_env(hand_regard.HandRegard(), steps=2)) == []
    update = lambda: bench_update(hand_regard.HandRegard(), "shared", 2, 4, repeats=1, threads=1)  # noqa: E731
    assert _warnings(update) == []


def test_an_unprepared_detector_still_warns_when_it_is_used():
    behavior = hand_regard.HandRegard()
    assert any("no calibrated hand detector" in m for m in _warnings(lambda: behavior.detector))
