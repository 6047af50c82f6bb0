"""The IntrinsicReward interface: one small, documented, stateful reward term."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from devlearn.infant import Infant


@dataclass
class StepContext:
    """What a reward term sees after one control step of one environment.

    Attributes:
        infant: The simulated infant after the step (read-only use: senses, contacts).
        observations: The behaviour's observations for this step, name -> array (unbatched).
        facts: Exactly what the behaviour's own :meth:`devlearn.Behavior.facts` returned for
            this step (the core adds none), e.g. self-touch's ``"touched"``: (68,) bool,
            ``"hand_contacts"``: (2, 68) bool, ``"hand_count"``: int. Computed once per step
            and shared by observations, all terms and the evaluator.
        step: Index of this step inside the episode, starting at 0.
        last_step: True on the episode's final step (time-out); terms paying at episode end
            (e.g. balance) pay here.
        stage: Options of the current curriculum stage (e.g. ``{"active_arms": ["left"]}``).
    """

    infant: Infant | None
    observations: dict[str, np.ndarray]
    facts: dict[str, Any]
    step: int
    last_step: bool
    stage: dict[str, Any] = field(default_factory=dict)


class IntrinsicReward(ABC):
    """A single intrinsic reward term, computed inside one environment.

    One instance lives in each environment, so its memory (e.g. "touched before") is that
    environment's. The environment sums ``weight * term(ctx)`` over the behaviour's terms and
    logs each term's per-episode sum separately under ``reward/<name>``.

    Subclasses set ``name`` and implement :meth:`__call__`; stateful terms override
    :meth:`reset` (per-episode memory) and :meth:`state_dict` / :meth:`load_state_dict`
    (lifetime memory that must survive ``devlearn run --resume``).

    A reward that is a model trained on batches of transitions (novelty, prediction error) is
    a :class:`~devlearn.api.learned.LearnedReward` instead: it lives in the learner, not here.
    """

    name: str = "reward"
    """Name used in logs (``reward/<name>``) and config."""

    def __init__(self, weight: float = 1.0) -> None:
        self.weight = float(weight)

    @abstractmethod
    def __call__(self, ctx: StepContext) -> float:
        """Return this term's unweighted reward for one step (a Python float)."""

    def reset(self) -> None:
        """Start a new episode: forget per-episode memory, keep lifetime memory."""

    def state_dict(self) -> dict[str, Any]:
        """Return everything needed to resume this term (picklable, numpy allowed)."""
        return {}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`state_dict` returned."""


@dataclass
class BatchContext:
    """What a batched reward term sees after one control step of a worker's environments.

    Attributes:
        contexts: One :class:`StepContext` per environment of the batch, in batch order (the
            same objects the per-environment terms see).
    """

    contexts: list[StepContext]
    _stacks: dict = field(default_factory=dict, repr=False)

    def __len__(self) -> int:
        return len(self.contexts)

    def stack(self, fact: str, dtype: Any = None) -> np.ndarray:
        """A fact of every environment stacked, (num_envs, *fact_shape); computed once per
        step and shared by the terms (treat it as read-only)."""
        key = (fact, dtype)
        if key not in self._stacks:
            if len(self.contexts) == 1:  # one env (a lone BehaviorEnv): a view, no copy
                value = self.contexts[0].facts[fact]
                ready = isinstance(value, np.ndarray) and (dtype is None or value.dtype == dtype)
                if not ready:
                    value = np.asarray(value, dtype=dtype)
                stacked = value[None]
            else:
                stacked = np.array([np.asarray(c.facts[fact], dtype=dtype) for c in self.contexts])
            self._stacks[key] = stacked
        return self._stacks[key]

    @property
    def last_step(self) -> np.ndarray:
        """(num_envs,) bool: the environment's episode ends on this step."""
        return np.fromiter((c.last_step for c in self.contexts), bool, len(self.contexts))

    @property
    def step(self) -> np.ndarray:
        """(num_envs,) int64: each environment's step index inside its episode."""
        return np.fromiter((c.step for c in self.contexts), np.int64, len(self.contexts))


class BatchedIntrinsicReward(ABC):
    """A reward term computed once per step for all environments of a worker, as arrays.

    The batched form of :class:`IntrinsicReward`, for terms whose per-step Python cost matters:
    a worker holds one instance for its ``num_envs`` environments, keeps every environment's
    memory in arrays with a leading ``num_envs`` axis (allocated by :meth:`bind`), and
    :meth:`__call__` returns one unweighted value per environment. Logging, weights and
    checkpoints are the same as for per-environment terms: ``state_dict(env)`` returns what a
    per-environment term would, so checkpoints do not depend on how the envs were split.

    Subclasses set ``name`` and implement :meth:`bind`, :meth:`__call__` and, when stateful,
    :meth:`reset`, :meth:`state_dict` and :meth:`load_state_dict`.

    **Run-wide memory.** A term may keep some memory for the whole run instead of per
    environment (self_touch's "region j was ever touched", so that a discovery is paid once
    per agent, not once per environment). It holds one copy for all the environments of its
    worker and reports it through :meth:`run_memory`. The core keeps the copies of all workers
    (and, under torchrun, all ranks) equal: at every PPO iteration boundary the runner gathers
    each worker's :meth:`run_memory`, combines them in worker (then rank) order with
    :meth:`merge_run_memory` and hands the result to every worker's :meth:`load_run_memory`
    (:meth:`devlearn.env.DevVecEnv.sync_run_memory`). Between two merges a worker knows only
    its own envs' discoveries, so one discovery can be paid at most once per worker (and rank)
    per iteration; results therefore depend on the number of workers, not only on the seed.
    Such a term's ``state_dict(env)`` holds the run memory too (every env the same copy), and
    ``load_state_dict(env, ...)`` for ``env`` 0 replaces the memory and for later envs merges
    into it, so loading any split of the saved envs gives the merged memory.
    """

    name: str = "reward"
    """Name used in logs (``reward/<name>``) and config."""

    def __init__(self, weight: float = 1.0) -> None:
        self.weight = float(weight)
        self.num_envs = 0

    def bind(self, num_envs: int) -> None:
        """Allocate per-environment memory for ``num_envs`` environments (called before use)."""
        self.num_envs = int(num_envs)

    @abstractmethod
    def __call__(self, batch: BatchContext) -> np.ndarray:
        """Return this term's unweighted rewards for one step, (num_envs,) float64."""

    def reset(self, env: int) -> None:
        """Environment ``env`` starts a new episode: forget its per-episode memory."""

    def state_dict(self, env: int) -> dict[str, Any]:
        """Return environment ``env``'s resumable state (picklable, numpy allowed)."""
        return {}

    def load_state_dict(self, env: int, state: dict[str, Any]) -> None:
        """Restore environment ``env``'s state from what :meth:`state_dict` returned."""

    def run_memory(self) -> dict[str, np.ndarray]:
        """Return the memory this term keeps for the whole run, name -> array (not a copy).

        Empty (the default) for terms that keep none; then the core never asks again.
        """
        return {}

    def merge_run_memory(self, copies: list[dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
        """Combine copies of :meth:`run_memory` (one per worker or rank, in order) into one.

        The default suits memory that only grows: elementwise OR of bool arrays, elementwise
        maximum of numeric ones. Override it for anything else; it must not depend on the
        order of ``copies`` for the result to be the same on every rank.

        Returns:
            One memory with the keys and shapes of the copies.
        """
        merged = {}
        for key in copies[0]:
            arrays = [np.asarray(c[key]) for c in copies]
            combine = np.logical_or if arrays[0].dtype == bool else np.maximum
            merged[key] = combine.reduce(np.stack(arrays), axis=0)
        return merged

    def load_run_memory(self, memory: dict[str, np.ndarray]) -> None:
        """Replace the run-wide memory by ``memory`` (a :meth:`merge_run_memory` result)."""
