"""Reward terms: one small, documented, stateful term, in its per-environment form
(:class:`IntrinsicReward`, easy to write) or its batched form (:class:`BatchedIntrinsicReward`,
the one contract the core knows; :class:`BatchedFromPerEnv` wraps the first into it), and how a
behaviour's config declares its terms (:class:`RewardTermCfg`: class, weight, params)."""

from __future__ import annotations

import copy
import inspect
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from devlearn.api.errors import UsageError

if TYPE_CHECKING:
    from devlearn.infant import Infant

_TERM_CLASSES: dict[str, type] = {}
"""Every reward-term class defined in this process, by its path ``module:QualName``: the only
classes a config's ``cls`` may name (filled by the base classes' ``__init_subclass__``, i.e. by
the code of the installed behaviours and plugins as Python imports it). A config never makes
devlearn import anything: a checkpoint or a config file is data."""


def term_path(cls: type) -> str:
    """The path a config stores for the reward-term class ``cls``: ``module:QualName``."""
    return f"{cls.__module__}:{cls.__qualname__}"


def _register_term(cls: type) -> None:
    _TERM_CLASSES[term_path(cls)] = cls


def _listed(cls: type) -> bool:
    """Whether a config may name the registered class ``cls``: a concrete, public term, not
    the core's adapter :class:`BatchedFromPerEnv` (it wraps a term, it is none)."""
    return (
        not inspect.isabstract(cls)
        and not any(part.startswith("_") for part in cls.__qualname__.split("."))
        and cls is not BatchedFromPerEnv
    )


def registered_terms() -> list[str]:
    """The paths a config's ``cls`` may name: every concrete, public reward-term class that the
    installed behaviours and plugins (or the caller's own code) defined. A behaviour's config
    names only those of them its own defaults declare
    (:func:`devlearn.api.behavior.check_reward_table`)."""
    return sorted(path for path, cls in _TERM_CLASSES.items() if _listed(cls))


def listed_term(path: str) -> type | None:
    """The class of :func:`registered_terms` that ``path`` names, or None: an unknown path,
    or a registered class no config may name (private, abstract, the adapter)."""
    found = _TERM_CLASSES.get(path)
    return found if found is not None and _listed(found) else None


@dataclass
class StepContext:
    """What a reward term sees after one control step of one environment.

    Attributes:
        infant: The simulated infant after the step (read-only use: senses, contacts).
        observations: The behaviour's observations for this step, name -> array (unbatched);
            inside a decision a read-only mapping, computed on first read.
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


class _RewardTerm:
    """What both term contracts share: a name, a weight, and registration. The two contracts
    (:class:`IntrinsicReward`, :class:`BatchedIntrinsicReward`) subclass this directly; every
    class below them is a reward term, registered as Python defines it (``_TERM_CLASSES``)."""

    name: str = "reward"
    """Name used in logs (``reward/<name>``) and config."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if _RewardTerm not in cls.__bases__:  # a term, not one of the two contracts
            _register_term(cls)

    def __init__(self, weight: float = 1.0) -> None:
        self.weight = float(weight)


class IntrinsicReward(_RewardTerm, ABC):
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


class BatchedIntrinsicReward(_RewardTerm, ABC):
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

    def __init__(self, weight: float = 1.0) -> None:
        super().__init__(weight)
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


class BatchedFromPerEnv(BatchedIntrinsicReward):
    """Per-environment terms as one batched term: how the core runs an :class:`IntrinsicReward`.

    The core knows only :class:`BatchedIntrinsicReward`; a behaviour may still return plain
    :class:`IntrinsicReward` terms, each wrapped once in this adapter. It holds one instance of
    the term per environment (the one it was given for environment 0, fresh copies of it for
    the others, made by :meth:`bind`), calls each on its own environment's context, and keeps
    the per-environment term's reset and state, so values, logs and checkpoints are those of
    the term run in each environment.

    Args:
        term: A fresh (never called) per-environment term; its name and weight are this one's.
    """

    def __init__(self, term: IntrinsicReward) -> None:
        super().__init__(term.weight)
        self.name = term.name
        self.terms = [term]
        """One instance per environment, in batch order."""
        self._fresh = copy.deepcopy(term)
        self.failed_env: int | None = None
        """Batch position of the environment whose term raised during the last call, or None."""

    def bind(self, num_envs: int) -> None:
        """Keep the first ``num_envs`` instances, adding fresh copies of the term as needed."""
        super().bind(num_envs)
        missing = max(0, self.num_envs - len(self.terms))
        self.terms = self.terms[: self.num_envs] + [
            copy.deepcopy(self._fresh) for _ in range(missing)
        ]

    def __call__(self, batch: BatchContext) -> np.ndarray:
        """Every environment's term on its own context: (num_envs,) float64."""
        values = np.empty(len(batch))
        self.failed_env = None
        for i, (term, ctx) in enumerate(zip(self.terms, batch.contexts)):
            try:
                values[i] = float(term(ctx))
            except Exception:
                self.failed_env = i
                raise
        return values

    def reset(self, env: int) -> None:
        self.terms[env].reset()

    def state_dict(self, env: int) -> dict[str, Any]:
        return self.terms[env].state_dict()

    def load_state_dict(self, env: int, state: dict[str, Any]) -> None:
        self.terms[env].load_state_dict(state)


def as_batched(term: IntrinsicReward | BatchedIntrinsicReward) -> BatchedIntrinsicReward:
    """``term`` in the batched form: itself, or wrapped in :class:`BatchedFromPerEnv`."""
    if isinstance(term, BatchedIntrinsicReward):
        return term
    return BatchedFromPerEnv(term)


@dataclass
class RewardTermCfg:
    """One reward term of a behaviour's config: its class, weight and parameters (mjlab's
    ``RewardTermCfg``). A behaviour's config declares its terms as a mapping term name ->
    ``RewardTermCfg`` in a field named ``rewards``, so that any term can be switched off or
    swept from the command line (``--set behavior.rewards.balance.weight=0``,
    ``--set behavior.rewards.balance.params.reward=5``) and
    :meth:`devlearn.Behavior.reward_terms` builds them (:func:`build_reward_terms`).

    Attributes:
        cls: The term's class (an :class:`IntrinsicReward` or :class:`BatchedIntrinsicReward`
            subclass), or its import path ``"package.module:Class"`` (what a saved config
            holds; a class given here is stored as its path).
        weight: The term's weight: the reward is the sum of ``weight * term``; 0 keeps the term
            (logged, paying nothing) unless the behaviour leaves zero-weight terms out.
        params: Keyword arguments of the class besides ``weight`` (its own constants).
    """

    cls: Any
    weight: float = 1.0
    params: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if isinstance(self.cls, type):
            self.cls = term_path(self.cls)
        self.weight = float(self.weight)
        self.params = dict(self.params)

    def term_class(self) -> type[IntrinsicReward] | type[BatchedIntrinsicReward]:
        """The class :attr:`cls` names, among the reward-term classes the installed behaviours
        and plugins defined (:func:`registered_terms`). Nothing is imported: a path that names
        no such class is refused, whatever module it names, and so is a registered class no
        config may name (a private or abstract one, the adapter :class:`BatchedFromPerEnv`).

        Raises:
            UsageError: The path names no listed reward-term class (one line, naming the
                valid ones).
        """
        found = listed_term(str(self.cls))
        if found is None:
            shown = repr(self.cls) if len(repr(self.cls)) <= 80 else repr(self.cls)[:77] + "..."
            raise UsageError(
                f"unknown reward term class {shown}: a config names only reward terms that the "
                f"installed behaviours and plugins define; valid: {', '.join(registered_terms())}"
            )
        return found

    def build(self, name: str, **shared: Any) -> IntrinsicReward | BatchedIntrinsicReward:
        """A fresh instance named ``name``: ``cls(weight=weight, **params, **shared)``.

        Args:
            name: The term's name in logs and config (``reward/<name>``).
            shared: Keyword arguments the behaviour adds from its own fields (options that
                several terms read, e.g. self-touch's ``lifetime_memory``).
        """
        term = self.term_class()(weight=self.weight, **self.params, **shared)
        term.name = name
        return term


def reward_term_cfg(value: RewardTermCfg | Mapping[str, Any]) -> RewardTermCfg:
    """A :class:`RewardTermCfg` from itself or from its saved form (a table with ``cls``,
    ``weight`` and ``params``, as a config file holds it)."""
    if isinstance(value, RewardTermCfg):
        return value
    unknown = set(value) - {"cls", "weight", "params"}
    if unknown or "cls" not in value:
        raise ValueError(f"a reward term is a table of cls, weight and params; got {sorted(value)}")
    return RewardTermCfg(value["cls"], value.get("weight", 1.0), dict(value.get("params", {})))


def build_reward_terms(
    rewards: Mapping[str, RewardTermCfg | Mapping[str, Any]],
    shared: Mapping[str, Mapping[str, Any]] | None = None,
) -> list[IntrinsicReward | BatchedIntrinsicReward]:
    """Fresh instances of a config's reward terms, in its order.

    Args:
        rewards: Term name -> :class:`RewardTermCfg` (or its saved table).
        shared: Term name -> keyword arguments the behaviour adds to that term's params.
    """
    shared = shared or {}
    return [
        reward_term_cfg(cfg).build(name, **shared.get(name, {})) for name, cfg in rewards.items()
    ]


def upgrade_saved_rewards(
    saved: Mapping[str, Any], moves: Mapping[str, str], config_class: type
) -> dict[str, Any]:
    """A saved behaviour config (as a config file holds it) in today's form: fields that the
    config class has since moved into its ``rewards`` table moved there.

    ``moves`` is what the class declares in ``BehaviorConfig.LEGACY_REWARD_KEYS`` (old field ->
    ``TERM.weight`` or ``TERM.params.NAME``, e.g. self-touch's ``weight_balance`` ->
    ``balance.weight``; empty for a config that is not a ``BehaviorConfig``). A saved
    config with such fields and no ``rewards`` gets the class's default terms with those
    weights and params set from the old fields, so a run saved before the move loads and acts
    as trained. Anything else is returned unchanged.
    """
    old = {key: saved[key] for key in moves if key in saved}
    upgraded = {key: value for key, value in saved.items() if key not in old}
    if not old:
        return upgraded
    if "rewards" not in upgraded:
        upgraded["rewards"] = {
            name: {"cls": term.cls, "weight": term.weight, "params": dict(term.params)}
            for name, term in config_class().rewards.items()
        }
    for key, value in old.items():
        term, _, where = moves[key].partition(".")
        entry = upgraded["rewards"].get(term)
        if entry is None:  # a term the saved table leaves out: nothing to set
            continue
        if where == "weight":
            entry["weight"] = value
        else:
            entry["params"][where.removeprefix("params.")] = value
    return upgraded
