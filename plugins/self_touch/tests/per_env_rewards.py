"""The formula oracle: Model I's four reward terms (paper sec. II-A3) per environment, one
class each, as the paper states them. The plugin computes them batched
(:mod:`devlearn_self_touch.rewards`); ``test_batched_rewards.py`` checks that it pays exactly
what these do, and ``test_self_touch_rewards.py`` checks these against hand-computed numbers.

R_t = R_touch + R_geom + R_milestones + R_balance. Every term reads only ``ctx.facts``
(computed once per step by :meth:`SelfTouch.facts`), so tests can drive them with synthetic
:class:`devlearn.StepContext` objects:

- ``touched``: (68,) bool, region j counts as touched this step;
- ``hand_contacts``: (2, 68) bool, hand h (left, right) touches region j (palm or fingers);
- ``hand_parts``: (2, 34) bool, hand h touches side-free part p this step.

"First ever" memory is lifetime state: kept across episodes by :meth:`reset`, saved by
:meth:`state_dict` and restored on ``devlearn run --resume``. Per-episode memory is not saved
(a resumed run starts fresh episodes).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from devlearn_self_touch.body_map import HANDS, NUM_PARTS, NUM_REGIONS
from devlearn_self_touch.config import NOT_IN_PAPER
from devlearn_self_touch.rewards import _check_touch_count, f_decay

from devlearn import IntrinsicReward, StepContext


class TouchNovelty(IntrinsicReward):
    """R_touch: novelty of each touched region, with the anti-boredom decay (sec. II-A3).

    For every region j touched this step (``facts["touched"]``), summed over regions::

        first_ever          if j was never touched before in this environment's lifetime
        first_in_episode    else if c_j = 0
        repeat_scale * f_decay(c_j)   otherwise

    where c_j counts the *earlier* steps of this episode on which j was touched (this step not
    included), so the second consecutive step pays 0.5 f_decay(1) and a contact held for the
    11th step pays 0.5 f_decay(10) = 0. A first-ever touch also starts the episode count.

    Args:
        weight: Term weight (paper: 1).
        first_ever: Paper: 5.0.
        first_in_episode: Paper: 1.0.
        repeat_scale: Paper: 0.5.
        midpoint, rate: Parameters of :func:`f_decay` (paper: 10, 0.5).
        touch_count: ``step`` (the paper's literal rule: every step a region is touched
            counts, so one region held for a whole episode costs about -489) or ``onset``
            (only a touch's first step counts and pays: holding costs nothing more).
    """

    name = "touch_novelty"

    def __init__(
        self,
        weight: float = 1.0,
        first_ever: float = 5.0,
        first_in_episode: float = 1.0,
        repeat_scale: float = 0.5,
        midpoint: float = 10.0,
        rate: float = 0.5,
        touch_count: str = "step",
    ) -> None:
        super().__init__(weight)
        self.first_ever, self.first_in_episode = float(first_ever), float(first_in_episode)
        self.repeat_scale, self.midpoint, self.rate = float(repeat_scale), midpoint, rate
        self.onset = _check_touch_count(touch_count)
        self.ever = np.zeros(NUM_REGIONS, dtype=bool)
        self.count = np.zeros(NUM_REGIONS, dtype=np.int64)
        self.before = np.zeros(NUM_REGIONS, dtype=bool)

    def __call__(self, ctx: StepContext) -> float:
        touched = np.asarray(ctx.facts["touched"], dtype=bool)
        if self.onset:
            touched, self.before = touched & ~self.before, touched.copy()
        reward = 0.0
        for j in np.flatnonzero(touched):
            if not self.ever[j]:
                reward += self.first_ever
            elif self.count[j] == 0:
                reward += self.first_in_episode
            else:
                decay = f_decay(float(self.count[j]), self.midpoint, self.rate)
                reward += self.repeat_scale * decay
        self.ever |= touched
        self.count += touched
        return float(reward)

    def reset(self) -> None:
        self.count[:] = 0
        self.before[:] = False

    def state_dict(self) -> dict[str, Any]:
        return {"ever": self.ever.copy()}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.ever = np.asarray(state["ever"], dtype=bool).copy()


class ContactNovelty(IntrinsicReward):
    """R_geom: the event of hand h first touching region j (sec. II-A3).

    Per (hand, region) pair of ``facts["hand_contacts"]`` (2 x 68; the paper's body part j
    ranges over the 68-region map), summed over pairs::

        first_ever          the pair's first contact in this environment's lifetime
        first_in_episode    its first contact in this episode
        0                   otherwise (sparse: holding or repeating a contact pays nothing)

    Args:
        weight: Term weight (paper: 1).
        first_ever: Paper: 10.0.
        first_in_episode: Paper: 2.0.
    """

    name = "contact_novelty"

    def __init__(
        self, weight: float = 1.0, first_ever: float = 10.0, first_in_episode: float = 2.0
    ) -> None:
        super().__init__(weight)
        self.first_ever, self.first_in_episode = float(first_ever), float(first_in_episode)
        self.ever = np.zeros((len(HANDS), NUM_REGIONS), dtype=bool)
        self.episode = np.zeros((len(HANDS), NUM_REGIONS), dtype=bool)

    def __call__(self, ctx: StepContext) -> float:
        contacts = np.asarray(ctx.facts["hand_contacts"], dtype=bool)
        new_ever = contacts & ~self.ever
        new_episode = contacts & ~self.episode & self.ever
        self.ever |= contacts
        self.episode |= contacts
        return float(self.first_ever * new_ever.sum() + self.first_in_episode * new_episode.sum())

    def reset(self) -> None:
        self.episode[:] = False

    def state_dict(self) -> dict[str, Any]:
        return {"ever": self.ever.copy()}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.ever = np.asarray(state["ever"], dtype=bool).copy()


class DiversityMilestones(IntrinsicReward):
    """R_milestones: a bonus each time the episode's coverage crosses a milestone (sec. II-A3).

    The count is the number of distinct regions (of 68, the paper's "body parts" j of the body
    map) marked ``facts["touched"]`` so far in the episode. Each milestone pays once per
    episode, on the step the count first reaches it; a step that crosses two pays twice.

    Args:
        weight: Term weight (paper: 1).
        reward: Bonus per milestone (paper: 5.0).
        milestones: Counts that pay (paper: 5, 10, 15, 20, 25, 30).
    """

    name = "diversity_milestones"

    def __init__(
        self,
        weight: float = 1.0,
        reward: float = 5.0,
        milestones: tuple[int, ...] = (5, 10, 15, 20, 25, 30),
    ) -> None:
        super().__init__(weight)
        self.reward = float(reward)
        self.milestones = tuple(sorted(int(m) for m in milestones))
        self.seen = np.zeros(NUM_REGIONS, dtype=bool)
        self.paid = 0  # milestones already paid this episode (they are crossed in order)

    def __call__(self, ctx: StepContext) -> float:
        self.seen |= np.asarray(ctx.facts["touched"], dtype=bool)
        reached = sum(1 for m in self.milestones if self.seen.sum() >= m)
        new = reached - self.paid
        self.paid = reached
        return float(self.reward * new)

    def reset(self) -> None:
        self.seen[:] = False
        self.paid = 0


class Balance(IntrinsicReward):
    """R_balance: a bonus at episode end for ambidextrous exploration (sec. II-A3).

    N_L and N_R are the numbers of distinct side-free parts (of 34) the left and right hand
    touched during the episode (``facts["hand_parts"]``), the same counts as the evaluation's
    per-hand coverage. On ``ctx.last_step`` the term pays ``reward`` if
    |N_L - N_R| <= ``tolerance`` (and N_L + N_R >= ``min_parts``), else 0; every other step 0.

    Args:
        weight: Term weight (paper: 1).
        reward: Paper: 10.0.
        tolerance: Paper: 3.
        min_parts: Paper: 0 (no such condition).
    """

    name = "balance"

    def __init__(
        self, weight: float = 1.0, reward: float = 10.0, tolerance: int = 3, min_parts: int = 0
    ) -> None:
        super().__init__(weight)
        self.reward, self.tolerance, self.min_parts = float(reward), int(tolerance), int(min_parts)
        self.parts = np.zeros((len(HANDS), NUM_PARTS), dtype=bool)

    def __call__(self, ctx: StepContext) -> float:
        self.parts |= np.asarray(ctx.facts["hand_parts"], dtype=bool)
        if not ctx.last_step:
            return 0.0
        n_left, n_right = (int(n) for n in self.parts.sum(axis=1))
        balanced = abs(n_left - n_right) <= self.tolerance
        return self.reward if balanced and n_left + n_right >= self.min_parts else 0.0

    def reset(self) -> None:
        self.parts[:] = False


ORACLES = {
    "touch_novelty": TouchNovelty,
    "contact_novelty": ContactNovelty,
    "diversity_milestones": DiversityMilestones,
    "balance": Balance,
}
"""The per-environment formula of each of the plugin's terms, by term name."""


def per_env_reward_terms(config: Any) -> list[IntrinsicReward]:
    """The oracle of ``SelfTouch(config).reward_terms()``: the same terms, weights and params
    as per-environment terms, each with its own memory (equal to the plugin's terms with
    ``lifetime_memory="per_env"``; they cannot share one). Issue #57's terms, which read the
    body, have no oracle here: they are tested in ``test_activity_terms.py``."""
    terms: list[IntrinsicReward] = []
    for name, cfg in config.rewards.items():
        if name in NOT_IN_PAPER and cfg.weight == 0:  # left out, as the plugin leaves them
            continue
        extra = {"touch_count": config.touch_count} if name == "touch_novelty" else {}
        terms.append(ORACLES[name](weight=cfg.weight, **cfg.params, **extra))
    return terms
