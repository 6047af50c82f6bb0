"""The first half of a batched step: physics per env, then facts and observations of all envs.

Facts and observations come from the first env's behaviour, once for the batch
(:meth:`~devlearn.Behavior.facts`, :meth:`~devlearn.Behavior.observe` on an
:class:`~devlearn.api.batching.EnvBatch`): the one path, whatever form the author wrote them in.
"""

from __future__ import annotations

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
    envs: list[BehaviorEnv], actions: Any
) -> tuple[list[StepContext], dict[str, np.ndarray]]:
    """Motor noise, hooks, ``process_action`` and physics per env (:func:`apply_action`),
    then facts and observations.

    Every observation is checked by the guard (:func:`devlearn.env.guards.check_observations`):
    a bad one raises, naming the env's index and its step.

    Args:
        envs: The envs of one batch (one behaviour class), in batch order.
        actions: (num_envs, action_dim) array, or one (action_dim,) action per env.
    Returns:
        ``(contexts, batch)``: one :class:`~devlearn.api.rewards.StepContext` per env (no rewards
        yet), and the observations as name -> (num_envs, *shape) arrays (each context's
        observations are row views of these).
    """
    for env, action in zip(envs, clipped_actions(actions)):
        apply_action(env, action)
    facts, batch = facts_and_observations(envs)
    observations = [{name: a[i] for name, a in batch.items()} for i in range(len(envs))]
    fine = all(a.dtype.kind not in "fc" or observation_within_bound(a) for a in batch.values())
    if not fine:  # find the first env with a bad value, and name it
        for env, obs in zip(envs, observations):
            check_observations(obs, env.index, env.episode_step + 1)
    contexts = [
        StepContext(
            env.infant,
            obs,
            f,
            env.episode_step,
            env.episode_step == env.episode_steps - 1,
            env.stage,
        )
        for env, obs, f in zip(envs, observations, facts)
    ]
    return contexts, batch


def facts_and_observations(
    envs: list[BehaviorEnv],
) -> tuple[list[dict[str, Any]], dict[str, np.ndarray]]:
    """The facts (one dict per env) and the observations (name -> (num_envs, *shape) array) of
    ``envs``, from the first env's behaviour, once for the batch."""
    lead = envs[0].behavior
    batch = EnvBatch([env.infant for env in envs], [env.behavior for env in envs])
    facts = lead.facts(batch)
    return facts, {name: np.asarray(a) for name, a in lead.observe(batch, facts).items()}
