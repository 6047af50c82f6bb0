"""The evaluation protocol of self-touch: settle period at reset, per-episode spread."""

from __future__ import annotations

import pytest
from devlearn_self_touch import SelfTouch, SelfTouchEvaluator
from scipy import stats
from self_touch_fakes import make_ctx


def run_episode(evaluator, contacts_at):
    """A 20-step episode; ``contacts_at``: step -> [(hand, part)] touched on that step."""
    for step in range(20):
        evaluator.record(
            make_ctx(hand_parts=contacts_at.get(step, []), step=step, last_step=step == 19)
        )
    return evaluator.end_episode()


def test_settle_period_does_not_credit_the_reset_contact():
    # The reset pose lands the left hand on part 5 (steps 0-2); the policy later touches
    # part 7 with the right hand (step 12).
    contacts = {0: [(0, 5)], 1: [(0, 5)], 2: [(0, 5)], 12: [(1, 7)]}
    settled = run_episode(SelfTouch().evaluation().evaluator(False), contacts)
    assert settled == {
        "coverage_left": 0.0,
        "coverage_right": 1.0,
        "coverage_total": 1.0,
        "score": 1 / 68,
        "balance": 1.0,
    }
    unsettled = run_episode(SelfTouchEvaluator(training=False, settle_steps=0), contacts)
    assert unsettled["coverage_left"] == 1.0 and unsettled["coverage_total"] == 2.0
    # A contact on step 10 (the first scored step) is credited.
    assert run_episode(SelfTouchEvaluator(training=False), {10: [(0, 3)]})["coverage_left"] == 1


def test_settle_is_recorded_and_training_credits_every_step():
    evaluator = SelfTouch().evaluation().evaluator(False)
    assert evaluator.settle_steps == 10 and evaluator.protocol()["settle_steps"] == 10
    run_episode(evaluator, {})
    assert evaluator.summary()["settle_steps"] == 10
    training = SelfTouch().evaluation().evaluator(True)
    assert run_episode(training, {0: [(0, 5)]})["coverage_left"] == 1.0
    with pytest.raises(ValueError, match="settle_steps"):
        SelfTouchEvaluator(training=False, settle_steps=-1)


def test_summary_keeps_the_union_and_adds_per_episode_spread():
    evaluator = SelfTouchEvaluator(training=False)
    run_episode(evaluator, {11: [(0, 1), (0, 2), (1, 2)]})  # left 2, right 1
    run_episode(evaluator, {15: [(1, 3)]})  # right 1
    run_episode(evaluator, {})
    summary = evaluator.summary()
    # Today's keys: the union over episodes.
    assert summary["coverage_left"] == 2 and summary["coverage_right"] == 2
    assert summary["coverage_total"] == 3 and summary["score"] == pytest.approx(4 / 68)
    assert summary["episode_score_mean"] == pytest.approx(4 / 68 / 3)
    scores = [3 / 68, 1 / 68, 0.0]
    low, high = stats.t.interval(0.95, 2, loc=sum(scores) / 3, scale=stats.sem(scores))
    assert summary["episode_score_ci_low"] == pytest.approx(low)
    assert summary["episode_score_ci_high"] == pytest.approx(high)
    assert summary["episode_coverage_total_std"] == pytest.approx(stats.tstd([2, 1, 0]))
    for key in ("coverage_left", "coverage_right", "coverage_total"):
        assert {f"episode_{key}_{s}" for s in ("mean", "std", "ci_low", "ci_high")} <= set(summary)


def test_union_score_and_its_bootstrap_interval_recompute_from_the_eval_json():
    """eval.json keeps every episode's touched parts per hand; the union score and its
    bootstrap interval follow from them alone."""
    import json

    import numpy as np
    from devlearn_self_touch.evaluation import union_score, union_score_interval

    evaluator = SelfTouchEvaluator(training=False)
    rng = np.random.default_rng(1)
    for _ in range(12):  # each episode: a few random (hand, part) touches after the settle
        touches = [(int(h), int(p)) for h, p in zip(rng.integers(0, 2, 4), rng.integers(0, 34, 4))]
        run_episode(evaluator, {11 + i: [t] for i, t in enumerate(touches)})
    saved = json.loads(json.dumps(evaluator.summary()))  # as written to eval.json
    parts = saved["episode_parts"]
    assert len(parts) == 12 and set(parts[0]) == {"left", "right"}
    assert union_score(parts) == saved["score"]
    interval = union_score_interval(parts)
    assert (interval["score_boot_low"], interval["score_boot_high"]) == (
        saved["score_boot_low"],
        saved["score_boot_high"],
    )
    # the union of a resample never exceeds the union of all episodes, and 12 episodes of ~4
    # touches leave resamples well below it: a mean of per-episode scores would not
    assert saved["score_boot_low"] < saved["score_boot_high"] <= saved["score"]
    assert saved["score_boot_low"] > saved["episode_score_mean"]
    # identical episodes: every resample has the same union
    same = [{"left": [1, 2], "right": [3]}] * 5
    assert union_score_interval(same) == {"score_boot_low": 3 / 68, "score_boot_high": 3 / 68}
