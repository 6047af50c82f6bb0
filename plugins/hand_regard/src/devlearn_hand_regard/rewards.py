"""Intrinsic reward terms of hand regard (paper sec. II-B4) plus the optional bilateral term.

The paper's reward is ``R_t = R_hand + R_motion - 0.05``; each part is its own term here so
that it is logged on its own (``reward/hand_count``, ``reward/motion``,
``reward/living_penalty``). ``bilateral_balance`` and ``reach_into_view`` are our additions
(the paper's future work: both hands in view).

Facts read (computed once per step by :meth:`HandRegard.facts`):
    ``hand_detections``: (2 eyes, 2 hands) bool, detector output, hands ordered [left, right].
    ``hand_flow``: (2 eyes, 2 hands) float, summed optical-flow magnitude (pixels per step)
        over each detected hand's pixels.
    ``hand_pixels``: (2 eyes, 2 hands) int, number of pixels of each detected hand.
    ``image_width``: int, eye image width in pixels (normalises the motion).
    ``view_prior``: (2 eyes, 2 hands) float or None, P(eye sees hand | posture) from the
        visibility model the infant learned while babbling (``attribution.py``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from devlearn import IntrinsicReward, StepContext

HANDS = ("left", "right")
"""Hand order used in every (eye, hand) array."""

HAND_COUNT_REWARD = (-0.1, 0.25, 0.5, 1.0, 2.0)
"""R_hand for n_t = 0, 1, 2, 3, 4 total detections over both eyes (paper sec. II-B4)."""
MOTION_KNEE = 0.08
"""m_t above which motion stops being rewarding and becomes a penalty (paper sec. II-B4)."""
LIVING_PENALTY = -0.05
"""Per-step living penalty (paper sec. II-B4)."""


def active_hands(stage: dict[str, Any]) -> list[int]:
    """Return the indices (0 left, 1 right) of the hands rewarded in a curriculum stage.

    Args:
        stage: Stage options; ``active_arms`` lists ``"left"`` and/or ``"right"`` (default both).
    """
    arms = stage.get("active_arms", HANDS)
    unknown = set(arms) - set(HANDS)
    if unknown:
        raise ValueError(f"unknown active_arms {sorted(unknown)}; valid: left, right")
    return [i for i, side in enumerate(HANDS) if side in arms]


def hand_count_reward(n: int) -> float:
    """R_hand for a total hand count ``n`` in 0..4 (paper sec. II-B4)."""
    return HAND_COUNT_REWARD[min(max(int(n), 0), 4)]


def motion_reward(m: float) -> float:
    """R_motion for a normalised hand motion ``m`` (paper sec. II-B4).

    ``min(0.05 m, 0.05)`` up to ``m = 0.08``, then ``-min(0.1 (m - 0.08), 0.1)``.
    """
    if m <= MOTION_KNEE:
        return min(0.05 * m, 0.05)
    return -min(0.1 * (m - MOTION_KNEE), 0.1)


def hand_motion(facts: dict[str, Any], hands: list[int]) -> float:
    """The motion signal m_t over the detected regions of ``hands``, both eyes pooled.

    m_t = (mean Farneback flow magnitude over those pixels, in pixels per step) / image width;
    0 when none of those hands is detected.
    """
    pixels = float(np.sum(facts["hand_pixels"][:, hands]))
    if pixels == 0:
        return 0.0
    flow = float(np.sum(facts["hand_flow"][:, hands]))
    return flow / pixels / float(facts["image_width"])


class HandCount(IntrinsicReward):
    """R_hand: -0.1, 0.25, 0.5, 1.0, 2.0 for n_t = 0..4 detected (eye, hand) pairs.

    In a one-arm curriculum stage only that hand's detections count (n_t in 0..2).
    """

    name = "hand_count"

    def __call__(self, ctx: StepContext) -> float:
        detections = ctx.facts["hand_detections"]
        return hand_count_reward(int(np.sum(detections[:, active_hands(ctx.stage)])))


class HandMotion(IntrinsicReward):
    """R_motion: rewards moderate optical flow inside the detected (active) hands' regions."""

    name = "motion"

    def __call__(self, ctx: StepContext) -> float:
        return motion_reward(hand_motion(ctx.facts, active_hands(ctx.stage)))


class LivingPenalty(IntrinsicReward):
    """A constant -0.05 every step (paper sec. II-B4)."""

    name = "living_penalty"

    def __call__(self, ctx: StepContext) -> float:
        return LIVING_PENALTY


class BilateralBalance(IntrinsicReward):
    """Extra term (paper's future work): reward seeing both hands, punish favouring one.

    Per hand, ``seen_h`` is 1 when any eye detects it. Exponential moving averages
    ``v_h <- v_h + (seen_h - v_h) / horizon`` track recent visibility (reset each episode).
    The reward is ``bonus * [both seen] - penalty * |v_left - v_right|``, and 0 in one-arm
    stages, where favouring the active hand is the point. The paper's agent settled on one
    hand (sec. III-B); this term makes the one-hand optimum worse than the two-hand one
    without changing the paper's terms.

    Args:
        weight: Term weight.
        bonus: Reward on steps where both hands are seen.
        penalty: Penalty per unit of visibility gap.
        horizon: Time constant of the averages, in steps (>= 1).
    """

    name = "bilateral_balance"

    def __init__(
        self, weight: float = 1.0, bonus: float = 0.25, penalty: float = 0.5, horizon: float = 200
    ) -> None:
        super().__init__(weight)
        if horizon < 1:
            raise ValueError(f"bilateral horizon must be >= 1 step, got {horizon}")
        self.bonus, self.penalty, self.horizon = float(bonus), float(penalty), float(horizon)
        self.visibility = np.zeros(2)

    def reset(self) -> None:
        self.visibility = np.zeros(2)

    def __call__(self, ctx: StepContext) -> float:
        if len(active_hands(ctx.stage)) < 2:
            return 0.0
        seen = np.any(ctx.facts["hand_detections"], axis=0).astype(float)  # (2 hands,)
        self.visibility += (seen - self.visibility) / self.horizon
        gap = abs(self.visibility[0] - self.visibility[1])
        return float(self.bonus * seen.all() - self.penalty * gap)

    def state_dict(self) -> dict[str, Any]:
        return {"visibility": self.visibility.copy()}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.visibility = np.asarray(state["visibility"], dtype=float).copy()


class ReachIntoView(IntrinsicReward):
    """Extra term (ours, issue #39): shaping toward both hands in view, from the infant's own
    expectation of what it will see.

    Pays ``bonus * min_h max_e P(eye e sees hand h | posture)``: the predicted visibility of
    the hand less likely in view, read from the visibility model the infant learned from its
    own one-arm babbling (``view_prior``; no segmentation, no image). With one hand held
    before the eyes and the other hanging it pays about nothing; it rises as the other arm
    lifts its hand toward view, a gradient where the hand count pays only once that hand is
    detected. It is 0 in one-arm stages and without a visibility model. Being a prediction it
    can be fooled (a posture the model wrongly expects in view), so ``bonus`` stays below
    what seeing the second hand adds to the hand count (0.5 to 1.5).

    The model's probabilities fall off exponentially away from the postures where a hand is
    seen (a hanging arm's hand is ~1e-4 likely in view), which leaves little to climb;
    ``temperature`` T > 1 pays on the flattened ``sigmoid(logit(P) / T)`` instead, the same
    order of postures with a slope that reaches the hanging arm.

    Args:
        weight: Term weight.
        bonus: Reward when both hands are surely expected in view.
        temperature: Divides the model's log-odds (1: its probabilities as they are).
    """

    name = "reach_into_view"

    def __init__(self, weight: float = 1.0, bonus: float = 0.25, temperature: float = 1.0) -> None:
        super().__init__(weight)
        if temperature <= 0:
            raise ValueError(f"reach_into_view temperature must be > 0, got {temperature}")
        self.bonus, self.temperature = float(bonus), float(temperature)

    def __call__(self, ctx: StepContext) -> float:
        prior = ctx.facts.get("view_prior")
        if prior is None or len(active_hands(ctx.stage)) < 2:
            return 0.0
        p = float(np.min(np.max(prior, axis=0)))
        if self.temperature != 1.0:
            p = min(max(p, 1e-300), 1.0 - 1e-16)
            logit = np.log(p) - np.log1p(-p)
            p = float(1.0 / (1.0 + np.exp(-logit / self.temperature)))
        return self.bonus * p
