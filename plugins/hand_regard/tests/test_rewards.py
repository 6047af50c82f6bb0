"""Reward terms checked against hand-computed values of the paper's formulas (sec. II-B4)."""

from __future__ import annotations

import numpy as np
import pytest
from devlearn_hand_regard.rewards import (
    BilateralBalance,
    HandCount,
    HandMotion,
    LivingPenalty,
    ReachIntoView,
    active_hands,
    hand_motion,
    motion_reward,
)

from devlearn.api.rewards import StepContext

BOTH = {"active_arms": ["left", "right"]}
LEFT = {"active_arms": ["left"]}
RIGHT = {"active_arms": ["right"]}


def ctx(detections, stage=BOTH, flow=None, pixels=None) -> StepContext:
    facts = {
        "hand_detections": np.asarray(detections, dtype=bool),
        "hand_flow": np.zeros((2, 2)) if flow is None else np.asarray(flow, float),
        "hand_pixels": np.zeros((2, 2), int) if pixels is None else np.asarray(pixels),
        "image_width": 64,
    }
    return StepContext(None, {}, facts, 0, False, stage)


@pytest.mark.parametrize(
    ("detections", "expected"),
    [
        ([[0, 0], [0, 0]], -0.1),
        ([[1, 0], [0, 0]], 0.25),
        ([[1, 0], [1, 0]], 0.5),
        ([[1, 1], [0, 1]], 1.0),
        ([[1, 1], [1, 1]], 2.0),
    ],
)
def test_hand_count_table(detections, expected):
    assert HandCount()(ctx(detections)) == pytest.approx(expected)


def test_hand_count_counts_only_the_active_hand():
    both_in_both = [[1, 1], [1, 1]]
    assert HandCount()(ctx(both_in_both, LEFT)) == pytest.approx(0.5)  # n_t = 2 left hands
    assert HandCount()(ctx([[0, 1], [0, 0]], LEFT)) == pytest.approx(-0.1)
    assert HandCount()(ctx([[0, 1], [0, 0]], RIGHT)) == pytest.approx(0.25)


@pytest.mark.parametrize(
    ("m", "expected"),
    [(0.0, 0.0), (0.04, 0.002), (0.08, 0.004), (0.1, -0.002), (1.0, -0.092), (2.0, -0.1)],
)
def test_motion_reward_values(m, expected):
    assert motion_reward(m) == pytest.approx(expected)


def test_motion_term_normalises_flow_by_pixels_and_width():
    # Left hand in the left eye: 100 pixels moving 3.2 px each -> m = 3.2 / 64 = 0.05.
    flow, pixels = [[320.0, 0.0], [0.0, 0.0]], [[100, 0], [0, 0]]
    c = ctx([[1, 0], [0, 0]], BOTH, flow, pixels)
    assert hand_motion(c.facts, [0, 1]) == pytest.approx(0.05)
    assert HandMotion()(c) == pytest.approx(0.0025)
    # In the right-arm stage only the right hand's (absent) motion counts.
    assert HandMotion()(ctx([[1, 0], [0, 0]], RIGHT, flow, pixels)) == 0.0
    # Pooled over both eyes: (320 + 960) / (100 + 100) / 64 = 0.1 -> -0.002.
    c = ctx([[1, 0], [1, 0]], BOTH, [[320.0, 0], [960.0, 0]], [[100, 0], [100, 0]])
    assert HandMotion()(c) == pytest.approx(-0.002)


def test_living_penalty():
    assert LivingPenalty()(ctx([[1, 1], [1, 1]])) == pytest.approx(-0.05)


def test_active_hands_rejects_unknown_arm():
    assert active_hands({}) == [0, 1]
    with pytest.raises(ValueError, match="unknown active_arms"):
        active_hands({"active_arms": ["middle"]})


def test_bilateral_balance_bonus_and_gap_penalty():
    term = BilateralBalance(bonus=0.25, penalty=0.5, horizon=10)
    # Both hands seen: v = (0.1, 0.1), no gap -> the bonus only.
    assert term(ctx([[1, 1], [0, 0]])) == pytest.approx(0.25)
    # Only the left hand: v = (0.19, 0.09), gap 0.1 -> -0.05.
    assert term(ctx([[1, 0], [1, 0]])) == pytest.approx(-0.05)
    state = term.state_dict()
    term.reset()
    assert term(ctx([[0, 0], [0, 0]])) == 0.0
    term.load_state_dict(state)
    np.testing.assert_allclose(term.visibility, [0.19, 0.09])
    # One-arm stages: the term is silent and its averages do not move.
    assert term(ctx([[1, 0], [0, 0]], LEFT)) == 0.0
    np.testing.assert_allclose(term.visibility, [0.19, 0.09])


def test_reach_into_view_pays_for_the_hand_less_likely_in_view():
    term = ReachIntoView(bonus=0.4)
    context = ctx([[1, 0], [1, 0]])
    # the left hand surely in view of the left eye, the right hand at best 0.3 likely
    context.facts["view_prior"] = np.array([[0.99, 0.1], [0.6, 0.3]])
    assert term(context) == pytest.approx(0.4 * 0.3)
    context.facts["view_prior"] = np.array([[0.99, 0.0], [0.9, 0.0]])  # the other hangs
    assert term(context) == 0.0
    # one-arm stages, and a detector without a visibility model: nothing
    context.facts["view_prior"] = np.ones((2, 2))
    assert term(ctx([[1, 0], [1, 0]], LEFT)) == 0.0
    assert term(StepContext(None, {}, {**context.facts, "view_prior": None}, 0, False, BOTH)) == 0
    assert term(context) == pytest.approx(0.4)


def test_reach_into_view_temperature_flattens_the_log_odds():
    context = ctx([[1, 0], [1, 0]])
    context.facts["view_prior"] = np.array([[0.99, 1e-6], [0.9, 1e-8]])  # the other hangs
    plain, tempered = ReachIntoView(bonus=1.0), ReachIntoView(bonus=1.0, temperature=4.0)
    assert plain(context) == pytest.approx(1e-6)
    # logit(1e-6) = -13.8: / 4 -> sigmoid(-3.45) = 0.031, a slope the hanging arm can climb
    assert tempered(context) == pytest.approx(1 / (1 + np.exp(np.log(1e6 - 1) / 4)), rel=1e-9)
    context.facts["view_prior"] = np.array([[0.99, 0.5], [0.9, 0.2]])  # even odds: unchanged
    assert tempered(context) == pytest.approx(0.5)
    higher = np.array([[0.99, 0.9], [0.9, 0.2]])
    assert (
        tempered(StepContext(None, {}, {**context.facts, "view_prior": higher}, 0, False, BOTH))
        < 0.9
    )
    with pytest.raises(ValueError, match="temperature must be > 0"):
        ReachIntoView(temperature=0)
