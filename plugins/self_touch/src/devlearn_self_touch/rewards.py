"""The four Model I reward terms (paper sec. II-A3): one instance per worker, arrays over its envs.

R_t = R_touch + R_geom + R_milestones + R_balance. Every term reads only facts (computed once
per step by :meth:`SelfTouch.facts`): ``touched`` (68,) bool, ``hand_contacts`` (2, 68) bool,
``hand_parts`` (2, 34) bool.

Each class computes, for every environment at once, exactly the number (bit for bit) that the
paper's per-environment formula gives (the oracle in ``plugins/self_touch/tests/
per_env_rewards.py``), and saves the same per-environment state;
``plugins/self_touch/tests/test_batched_rewards.py`` checks both.
Where a per-environment term sums floats in a Python loop, the batched one sums them in the
same order (a loop over the few touched pairs), and f_decay is tabulated with the same
``math.exp``. The arrays are tiny, so the terms keep numpy calls few and return early when
nothing was touched (most steps).

The two "first ever" memories (R_touch's regions, R_geom's hand-region pairs) are the run's by
default (``lifetime_memory="shared"``): one memory per worker for all its envs, merged across
workers and ranks at every iteration boundary (see
:class:`devlearn.BatchedIntrinsicReward`), so a discovery pays first-ever once per agent
rather than once per environment. When several envs of a worker make the same discovery on
the same step, the first in batch order (the lowest env index) is paid first-ever and the
others what an already-known region pays. ``lifetime_memory="per_env"`` keeps one memory per
environment, as every run before issue #20 did; only that mode equals the per-environment
twins.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from devlearn import BatchContext, BatchedIntrinsicReward
from devlearn_self_touch.body_map import HANDS, NUM_PARTS, NUM_REGIONS


def f_decay(c: float, midpoint: float = 10.0, rate: float = 0.5) -> float:
    """Anti-boredom factor f_decay(c) = 2 / (1 + exp(rate (c - midpoint))) - 1 (sec. II-A3).

    Starts near +1 (f(0) = 0.98661), crosses 0 at ``midpoint`` and tends to -1, so holding a
    contact is first rewarded, then penalised.

    Args:
        c: Number of earlier steps of this episode on which the region was touched.
        midpoint: Zero crossing (paper: 10).
        rate: Steepness (paper: 0.5).

    Returns:
        A float in (-1, 1).
    """
    x = rate * (c - midpoint)
    if x > 700.0:  # exp overflows; the limit is exactly -1
        return -1.0
    return 2.0 / (1.0 + math.exp(x)) - 1.0


TOUCH_COUNTS = ("step", "onset")
"""Valid values of the touch-novelty term's ``touch_count``."""

TICK_SECONDS = 0.005
"""Seconds between two calls of a term when its contexts carry no infant (synthetic steps in
tests): BabyBench's physics step. With an infant, its ``physics_timestep``."""


def steps_of(seconds: float, tick: float) -> float:
    """``seconds`` in ticks of ``tick`` s, rounded to 1e-9 of a tick so that a time set in
    seconds gives the step count exactly (0.05 s at 5 ms: 10.0)."""
    return round(float(seconds) / float(tick), 9)


def _check_touch_count(touch_count: str) -> bool:
    """True for ``onset``; raises ValueError naming the valid values otherwise."""
    if touch_count not in TOUCH_COUNTS:
        raise ValueError(f"unknown touch_count '{touch_count}'; valid: {', '.join(TOUCH_COUNTS)}")
    return touch_count == "onset"


LIFETIME_MEMORIES = ("shared", "per_env")
"""Valid values of the terms' ``lifetime_memory`` (and of SelfTouchConfig.lifetime_memory)."""


def _check_memory(lifetime_memory: str) -> bool:
    """Return True for ``"shared"``; raise ValueError naming the valid values otherwise."""
    if lifetime_memory not in LIFETIME_MEMORIES:
        raise ValueError(
            f"unknown lifetime_memory '{lifetime_memory}'; valid: {', '.join(LIFETIME_MEMORIES)}"
        )
    return lifetime_memory == "shared"


class _LifetimeNovelty(BatchedIntrinsicReward):
    """A novelty term's lifetime memory ``self.ever`` (one row per env, or one shared row when
    ``self.shared``), saved per env and, when shared, as the run's memory."""

    ever: np.ndarray
    shared: bool

    def state_dict(self, env: int) -> dict[str, Any]:
        return {"ever": self.ever[0 if self.shared else env].copy()}

    def load_state_dict(self, env: int, state: dict[str, Any]) -> None:
        """Restore env ``env``'s saved memory: its own row, or into the shared row (env 0
        replaces it, later envs are ORed in, so a batch loads the union of its envs' memories)."""
        saved = np.asarray(state["ever"], dtype=bool)
        if not self.shared:
            self.ever[env] = saved
        elif env == 0:
            self.ever[0] = saved
        else:
            self.ever[0] |= saved

    def run_memory(self) -> dict[str, np.ndarray]:
        return {"ever": self.ever[0]} if self.shared else {}

    def load_run_memory(self, memory: dict[str, np.ndarray]) -> None:
        self.ever[0] = np.asarray(memory["ever"], dtype=bool)


class TouchNovelty(_LifetimeNovelty):
    """R_touch: novelty of each touched region, with the anti-boredom decay (sec. II-A3).

    For every region j touched this step (``facts["touched"]``), summed over regions::

        first_ever          if j was never touched before in the lifetime (``lifetime_memory``)
        first_in_episode    else if c_j = 0
        repeat_scale * f_decay(c_j)   otherwise

    where c_j counts the *earlier* steps of this episode on which j was touched (this step not
    included), so the second consecutive step pays 0.5 f_decay(1) and a contact held for the
    11th step pays 0.5 f_decay(10) = 0. A first-ever touch also starts the episode count.

    With ``touch_count="step"`` c_j is a time: the term is called on every physics step
    (self-touch's facts run at each one, whatever ``env.action_repeat``), so given
    ``crossing_s`` and ``steepness_s`` the term takes f_decay's midpoint = crossing_s / dt and
    rate = dt / steepness_s from the body's physics step dt on its first call (0.05 s and
    0.01 s: 10 and 0.5 at 200 Hz, the paper's), and a contact turns from reward to penalty
    after the same simulated time whatever the physics step.

    Args:
        weight: Term weight (paper: 1).
        first_ever: Paper: 5.0.
        first_in_episode: Paper: 1.0.
        repeat_scale: Paper: 0.5.
        midpoint, rate: Parameters of :func:`f_decay` (paper: 10, 0.5).
        touch_count: ``step`` (the paper's literal rule: every step a region is touched
            counts, so one region held for a whole episode costs about -489) or ``onset``
            (only a touch's first step counts and pays: holding costs nothing more).
        lifetime_memory: ``shared`` (one memory for the run) or ``per_env`` (module docstring).
        crossing_s, steepness_s: With ``touch_count="step"``, f_decay's zero crossing and its
            time constant 1 / rate in simulated seconds, replacing ``midpoint`` and ``rate``
            (None: those, in steps). Ignored with ``onset``, where c_j counts touches.
    """

    name = "touch_novelty"

    def __init__(
        self,
        weight: float = 1.0,
        *,
        first_ever: float = 5.0,
        first_in_episode: float = 1.0,
        repeat_scale: float = 0.5,
        midpoint: float = 10.0,
        rate: float = 0.5,
        lifetime_memory: str = "shared",
        touch_count: str = "step",
        crossing_s: float | None = None,
        steepness_s: float | None = None,
    ) -> None:
        super().__init__(weight)
        self.first_ever, self.first_in_episode = float(first_ever), float(first_in_episode)
        self.repeat_scale, self.midpoint, self.rate = float(repeat_scale), midpoint, rate
        self.shared = _check_memory(lifetime_memory)
        self.onset = _check_touch_count(touch_count)
        self.clock: tuple[float, float] | None = None
        """(crossing_s, steepness_s) still to convert with the body's physics step, or None."""
        if crossing_s is not None or steepness_s is not None:
            if crossing_s is None or steepness_s is None or not min(crossing_s, steepness_s) > 0:
                raise ValueError(
                    "crossing_s and steepness_s are given together, both above 0; got "
                    f"{crossing_s}, {steepness_s}"
                )
            if not self.onset:
                self.clock = (float(crossing_s), float(steepness_s))
        self._repeat = np.zeros(0)  # repeat_scale * f_decay(c) for c = 0, 1, ... (grown as needed)
        self.bind(1)

    def _set_clock(self, clock: tuple[float, float], batch: BatchContext) -> None:
        """midpoint and rate from ``clock`` (seconds), in physics steps of the batch's body."""
        infant = batch.contexts[0].infant
        tick = float(infant.physics_timestep) if infant is not None else TICK_SECONDS
        self.midpoint, self.rate = steps_of(clock[0], tick), steps_of(tick, clock[1])
        self._repeat = np.zeros(0)
        self.clock = None

    def bind(self, num_envs: int) -> None:
        super().bind(num_envs)
        # ever: (1, 68) shared by the batch, or (num_envs, 68); count is always per env
        self.ever = np.zeros((1 if self.shared else num_envs, NUM_REGIONS), dtype=bool)
        self.count = np.zeros((num_envs, NUM_REGIONS), dtype=np.int64)
        self.before = np.zeros((num_envs, NUM_REGIONS), dtype=bool)  # touched last step

    def _repeat_pay(self, count: np.ndarray) -> np.ndarray:
        """repeat_scale * f_decay(count), elementwise, with the per-env term's float math."""
        need = int(count.max()) + 1
        if need > len(self._repeat):
            size = max(need, 2 * len(self._repeat), 64)
            self._repeat = np.array(
                [
                    self.repeat_scale * f_decay(float(c), self.midpoint, self.rate)
                    for c in range(size)
                ]
            )
        return self._repeat.take(count)

    def __call__(self, batch: BatchContext) -> np.ndarray:
        if self.clock is not None:
            self._set_clock(self.clock, batch)
        touched = batch.stack("touched", bool)
        if self.onset:  # only a touch's first step counts
            touched, self.before = touched & ~self.before, touched.copy()
        rows, cols = touched.nonzero()  # row-major: regions ascending
        if len(rows) == 0:
            return np.zeros(len(batch))
        count = self.count[rows, cols]
        if self.shared:
            # Of the envs touching region j first this step, the lowest (pairs come in row
            # order, so np.unique's first occurrence) is paid first-ever.
            new = np.zeros(len(cols), dtype=bool)
            _, first = np.unique(cols, return_index=True)
            new[first] = ~self.ever[0, cols[first]]
            self.ever[0, cols] = True
        else:
            new = ~self.ever[rows, cols]
            self.ever[rows, cols] = True
        pay = np.where(
            new,
            self.first_ever,
            np.where(count == 0, self.first_in_episode, self._repeat_pay(count)),
        )
        reward = [0.0] * len(batch)
        for row, value in zip(rows.tolist(), pay.tolist()):  # the per-env loop's order of sums
            reward[row] += value
        self.count[rows, cols] += 1
        return np.array(reward)

    def reset(self, env: int) -> None:
        self.count[env] = 0
        self.before[env] = False


class ContactNovelty(_LifetimeNovelty):
    """R_geom: the event of hand h first touching region j (sec. II-A3).

    Per (hand, region) pair of ``facts["hand_contacts"]`` (2 x 68; the paper's body part j
    ranges over the 68-region map), summed over pairs::

        first_ever          the pair's first contact in the lifetime (``lifetime_memory``)
        first_in_episode    its first contact in this episode
        0                   otherwise (sparse: holding or repeating a contact pays nothing)

    Args:
        weight: Term weight (paper: 1).
        first_ever: Paper: 10.0.
        first_in_episode: Paper: 2.0.
        lifetime_memory: ``shared`` or ``per_env``, as for :class:`TouchNovelty`.
    """

    name = "contact_novelty"

    def __init__(
        self,
        weight: float = 1.0,
        first_ever: float = 10.0,
        first_in_episode: float = 2.0,
        lifetime_memory: str = "shared",
    ) -> None:
        super().__init__(weight)
        self.first_ever, self.first_in_episode = float(first_ever), float(first_in_episode)
        self.shared = _check_memory(lifetime_memory)
        self.bind(1)

    def bind(self, num_envs: int) -> None:
        super().bind(num_envs)
        # ever: (1, 2, 68) shared by the batch, or (num_envs, 2, 68); episode is per env
        self.ever = np.zeros((1 if self.shared else num_envs, len(HANDS), NUM_REGIONS), bool)
        self.episode = np.zeros((num_envs, len(HANDS), NUM_REGIONS), dtype=bool)

    def __call__(self, batch: BatchContext) -> np.ndarray:
        contacts = batch.stack("hand_contacts", bool)  # (E, 2, 68)
        if not contacts.any():
            return np.zeros(len(batch))
        known = self.ever  # (E, 2, 68), or (1, 2, 68) broadcast over the batch
        if self.shared and len(contacts) > 1:
            # a pair first contacted this step by several envs is new only to the first
            earlier = np.zeros_like(contacts)
            earlier[1:] = np.logical_or.accumulate(contacts[:-1], axis=0)
            known = known | earlier
        new_ever = (contacts & ~known).sum(axis=(1, 2))
        new_episode = (contacts & ~self.episode & known).sum(axis=(1, 2))
        self.ever |= contacts.any(axis=0, keepdims=True) if self.shared else contacts
        self.episode |= contacts
        return self.first_ever * new_ever + self.first_in_episode * new_episode

    def reset(self, env: int) -> None:
        self.episode[env] = False


class DiversityMilestones(BatchedIntrinsicReward):
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
        self._levels = np.asarray(self.milestones, dtype=np.int64)
        self.bind(1)

    def bind(self, num_envs: int) -> None:
        super().bind(num_envs)
        self.seen = np.zeros((num_envs, NUM_REGIONS), dtype=bool)
        self.paid = np.zeros(num_envs, dtype=np.int64)

    def __call__(self, batch: BatchContext) -> np.ndarray:
        touched = batch.stack("touched", bool)
        if not touched.any():
            return np.zeros(len(batch))
        self.seen |= touched
        # milestones m <= count: the insertion point of count among the sorted milestones
        reached = np.searchsorted(self._levels, self.seen.sum(axis=1), side="right")
        new = reached - self.paid
        self.paid = reached
        return self.reward * new

    def reset(self, env: int) -> None:
        self.seen[env] = False
        self.paid[env] = 0


class Balance(BatchedIntrinsicReward):
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
        self.bind(1)

    def bind(self, num_envs: int) -> None:
        super().bind(num_envs)
        self.parts = np.zeros((num_envs, len(HANDS), NUM_PARTS), dtype=bool)

    def __call__(self, batch: BatchContext) -> np.ndarray:
        self.parts |= batch.stack("hand_parts", bool)
        if not any(ctx.last_step for ctx in batch.contexts):  # pays only at episode ends
            return np.zeros(len(batch))
        last = batch.last_step
        n = self.parts.sum(axis=2)  # (E, 2): parts touched by the left and right hand
        balanced = np.abs(n[:, 0] - n[:, 1]) <= self.tolerance
        pays = last & balanced & (n.sum(axis=1) >= self.min_parts)
        return np.where(pays, self.reward, 0.0)

    def reset(self, env: int) -> None:
        self.parts[env] = False
