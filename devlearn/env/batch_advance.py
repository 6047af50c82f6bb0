"""The first half of a batched step: physics per env, then facts and observations of all envs.

Facts and observations come from the first env's behaviour, once for the batch
(:meth:`~devlearn.Behavior.facts`, :meth:`~devlearn.Behavior.observe` on an
:class:`~devlearn.api.batching.EnvBatch`): the one path, whatever form the author wrote them in.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from devlearn.api.batching import EnvBatch
from devlearn.api.rewards import StepContext
from devlearn.env.guards import check_observations, observation_within_bound

if TYPE_CHECKING:
    from devlearn.env.behavior_env import BehaviorEnv


def clipped_actions(actions: Any) -> np.ndarray | list[np.ndarray]:
    """Every env's action as float64 clipped to [-1, 1]: rows of one array for a
    (num_envs, action_dim) array (one clip for the batch), else one array per action."""
    # np.minimum(np.maximum(...)) is np.clip (NaN stays NaN) without its Python overhead
    if isinstance(actions, np.ndarray) and actions.ndim == 2:
        return np.minimum(np.maximum(actions.astype(np.float64), -1.0), 1.0)
    return [np.minimum(np.maximum(np.asarray(a, dtype=np.float64), -1.0), 1.0) for a in actions]


def apply_action(env: BehaviorEnv, action: np.ndarray) -> None:
    """One physics step of ``env`` under ``action`` (clipped): the env's motor noise added
    (:meth:`~devlearn.env.behavior_env.BehaviorEnv.motor_command`), the behaviour's episode
    hooks, the body's step."""
    action = env.motor_command(action)
    env.hooks.before_step(env.infant, action)
    env.infant.step(env.hooks.process_action(action, env.stage))


def advance_batch(
    envs: list[BehaviorEnv], actions: Any, observe: bool = True
) -> tuple[list[StepContext], dict[str, np.ndarray] | None]:
    """Motor noise, hooks, ``process_action`` and physics per env (:func:`apply_action`),
    then facts and observations.

    Every observation is checked by the guard (:func:`devlearn.env.guards.check_observations`):
    a bad one raises, naming the env's index and its step.

    Args:
        envs: The envs of one batch (one behaviour class), in batch order.
        actions: (num_envs, action_dim) array, or one (action_dim,) action per env.
        observe: False: a physics step inside a decision, whose observations the policy never
            sees; they are computed (once for the batch, checked) only if a reward term or the
            evaluator reads a context's ``observations`` (:class:`DeferredObservations`).
    Returns:
        ``(contexts, batch)``: one :class:`~devlearn.api.rewards.StepContext` per env (no rewards
        yet), and the observations as name -> (num_envs, *shape) arrays (each context's
        observations are row views of these); ``batch`` is None when not ``observe``.
    """
    for env, action in zip(envs, clipped_actions(actions)):
        apply_action(env, action)
    lead, env_batch, facts = batch_facts(envs)
    steps = [(env.index, env.episode_step + 1) for env in envs]  # the guard's names
    observations: list[Mapping[str, np.ndarray]]
    if observe:
        batch = observe_checked(lead, env_batch, facts, steps)
        observations = [{name: a[i] for name, a in batch.items()} for i in range(len(envs))]
    else:
        batch = None
        deferred = DeferredObservations(lead, env_batch, facts, steps)
        observations = [deferred.row(i) for i in range(len(envs))]
    contexts = [
        StepContext(
            env.infant,
            obs,  # type: ignore[arg-type]  # a read-only mapping inside a decision
            f,
            env.episode_step,
            env.episode_step == env.episode_steps - 1,
            env.stage,
        )
        for env, obs, f in zip(envs, observations, facts)
    ]
    return contexts, batch


def observe_checked(
    lead: Any, batch: EnvBatch, facts: list[dict[str, Any]], steps: list[tuple[int, int]]
) -> dict[str, np.ndarray]:
    """The behaviour's observations of ``batch`` (name -> (num_envs, *shape) array), checked by
    the guard; ``steps``: each env's (index, step) to name in a :class:`GuardError`."""
    arrays = observe(lead, batch, facts)
    fine = all(a.dtype.kind not in "fc" or observation_within_bound(a) for a in arrays.values())
    if not fine:  # find the first env with a bad value, and name it
        for i, (index, step) in enumerate(steps):
            check_observations({name: a[i] for name, a in arrays.items()}, index, step)
    return arrays


class DeferredObservations:
    """The observations of a physics step inside a decision, computed for the whole batch the
    first time any env's are read (by a reward term or the evaluator), else never: the
    policy sees only a decision's last step (issue #54 item 5: self-touch spent ~10% of its
    env time observing steps nobody read)."""

    def __init__(
        self, lead: Any, batch: EnvBatch, facts: list[dict[str, Any]], steps: list[tuple[int, int]]
    ) -> None:
        self._args = (lead, batch, facts, steps)
        self._arrays: dict[str, np.ndarray] | None = None

    def arrays(self) -> dict[str, np.ndarray]:
        if self._arrays is None:
            self._arrays = observe_checked(*self._args)
        return self._arrays

    def row(self, i: int) -> Mapping[str, np.ndarray]:
        return _Row(self, i)


class _Row(Mapping[str, np.ndarray]):
    """One env's deferred observations: a read-only mapping, name -> its row."""

    def __init__(self, source: DeferredObservations, i: int) -> None:
        self._source, self._i = source, i

    def __getitem__(self, name: str) -> np.ndarray:
        return self._source.arrays()[name][self._i]

    def __iter__(self) -> Iterator[str]:
        return iter(self._source.arrays())

    def __len__(self) -> int:
        return len(self._source.arrays())


def batch_facts(envs: list[BehaviorEnv]) -> tuple[Any, EnvBatch, list[dict[str, Any]]]:
    """``(lead, batch, facts)``: the first env's behaviour, ``envs`` as one
    :class:`~devlearn.api.batching.EnvBatch`, and its facts (one dict per env), once for the
    batch."""
    lead = envs[0].behavior
    batch = EnvBatch([env.infant for env in envs], [env.behavior for env in envs])
    return lead, batch, lead.facts(batch)


def observe(lead: Any, batch: EnvBatch, facts: list[dict[str, Any]]) -> dict[str, np.ndarray]:
    """The behaviour's observations of ``batch``: name -> (num_envs, *shape) array."""
    return {name: np.asarray(a) for name, a in lead.observe(batch, facts).items()}


def facts_and_observations(
    envs: list[BehaviorEnv],
) -> tuple[list[dict[str, Any]], dict[str, np.ndarray]]:
    """The facts (one dict per env) and the observations (name -> (num_envs, *shape) array) of
    ``envs``, from the first env's behaviour, once for the batch."""
    lead, batch, facts = batch_facts(envs)
    return facts, observe(lead, batch, facts)
