"""Gymnasium environments of every installed behaviour, so that any Gymnasium learner can train
devlearn's infant (docs/gymnasium.md).

``import devlearn.gym`` registers ``devlearn/<Behaviour>-v0`` for every behaviour the plugin
registry finds (``devlearn/SelfTouch-v0``, ``devlearn/HandRegard-v0``, one per third-party
behaviour: the CamelCase of its name)::

    import gymnasium
    import devlearn.gym

    env = gymnasium.make("devlearn/SelfTouch-v0", overrides={"seed": 1})
    envs = devlearn.gym.make_vec("devlearn/SelfTouch-v0", num_envs=16, workers=2)

The config goes through ``devlearn run``'s config path: ``overrides`` are its ``--set`` items,
``preset`` its ``--preset``. Modules: :mod:`~devlearn.gym.env` (one env),
:mod:`~devlearn.gym.vector` (the vector env over devlearn's worker pool),
:mod:`~devlearn.gym.run_setup` (config, prepared behaviour, spaces, the curriculum's clock).
:func:`save_policy` writes a policy another learner trained as a file ``devlearn eval``
evaluates under devlearn's protocol and baselines.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, cast

import gymnasium

if TYPE_CHECKING:
    from pathlib import Path

    import torch
    from gymnasium.vector import VectorEnv

    from devlearn.gym.env import DevlearnEnv
    from devlearn.gym.vector import DevlearnVectorEnv
    from devlearn.plugins import PluginRegistry

NAMESPACE = "devlearn"
"""The namespace of devlearn's environment ids."""
VERSION = 0
"""The version of every id (``-v0``)."""
ENTRY_POINT = "devlearn.gym.env:DevlearnEnv"
VECTOR_ENTRY_POINT = "devlearn.gym.vector:DevlearnVectorEnv"


def env_id(behavior_name: str) -> str:
    """The Gymnasium id of a behaviour: ``self_touch`` -> ``devlearn/SelfTouch-v0``."""
    camel = "".join(part.capitalize() for part in behavior_name.split("_"))
    return f"{NAMESPACE}/{camel}-v{VERSION}"


def register_behaviors(registry: PluginRegistry | None = None) -> dict[str, str]:
    """Register every behaviour of ``registry`` (default: the installed plugins) with
    Gymnasium, single and vector entry points; ``import devlearn.gym`` calls it.

    Returns:
        Id -> behaviour name.
    """
    if registry is None:
        from devlearn.plugins import PluginRegistry

        registry = PluginRegistry()
    ids = {}
    for name in registry.behaviors():
        ids[env_id(name)] = name
        if env_id(name) in gymnasium.registry:  # registered already (a reload)
            continue
        gymnasium.register(
            env_id(name),
            entry_point=ENTRY_POINT,
            vector_entry_point=VECTOR_ENTRY_POINT,
            kwargs={"behavior": name},
        )
    return ids


def make_vec(env_id: str, num_envs: int = 1, workers: int = 0, **kwargs: Any) -> VectorEnv:
    """``num_envs`` environments of ``env_id`` over devlearn's own worker pool
    (:class:`~devlearn.gym.vector.DevlearnVectorEnv`): ``workers`` processes, 0 in this
    process, -1 one per core as ``devlearn run``. ``kwargs``: ``overrides``, ``preset``.
    """
    return gymnasium.make_vec(
        env_id,
        num_envs=num_envs,
        vectorization_mode="vector_entry_point",
        workers=workers,
        **kwargs,
    )


def devlearn_env(env: gymnasium.Env | VectorEnv) -> DevlearnEnv | DevlearnVectorEnv:
    """The devlearn env under Gymnasium's wrappers.

    Raises:
        UsageError: ``env`` is no devlearn.gym env.
    """
    from devlearn.api.errors import UsageError
    from devlearn.gym.env import DevlearnEnv
    from devlearn.gym.vector import DevlearnVectorEnv

    base = env.unwrapped
    if not isinstance(base, DevlearnEnv | DevlearnVectorEnv):
        raise UsageError(f"{base!r} is not a devlearn.gym env (gymnasium.make('devlearn/...'))")
    return base


def observation_names(env: gymnasium.Env | VectorEnv) -> list[str]:
    """The observation groups of ``env`` in the order :func:`save_policy`'s policy takes them
    (its Dict space's order)."""
    return list(devlearn_env(env).observation_dict.spaces)


def save_policy(
    policy: torch.nn.Module,
    env: gymnasium.Env | VectorEnv,
    path: str | Path,
    *,
    learner: str,
    env_steps: int | None = None,
) -> Path:
    """Write a policy another learner trained on ``env`` as a scripted policy file, which
    ``devlearn eval BEHAVIOR --checkpoint PATH`` evaluates under devlearn's protocol, beside
    the same baselines (:mod:`devlearn.evaluation.scripted_policy`).

    Args:
        policy: ``policy(*observations)`` -> (N, action_dim) actions in [-1, 1], the action
            the evaluation should take (deterministic); each observation (N, *shape) in
            :func:`observation_names` order and its space's dtype. Any normalisation the
            learner applies outside its network belongs inside (frozen).
        env: The devlearn.gym env (single or vector) it trained on: its resolved config
            (decision rate, the behaviour's options) and the behaviour's artifacts are
            recorded, so the evaluation builds the env it trained on.
        path: The file to write (``OUT/policy.pt``).
        learner: Who trained it, e.g. ``sb3_ppo`` (``devlearn report``'s variants).
        env_steps: Physics steps it trained for, summed over envs (devlearn's count); default
            the steps ``env`` has taken.
    Returns:
        The path written.
    """
    import numpy as np
    from gymnasium import spaces

    from devlearn.config.run_config import to_dict
    from devlearn.evaluation.scripted_policy import ObservationOrder, save_scripted_policy

    base = devlearn_env(env)
    space = base.observation_dict
    names = observation_names(base)
    boxes = {n: cast(spaces.Box, space[n]) for n in names}
    observation = {n: np.zeros(box.shape, box.dtype) for n, box in boxes.items()}
    steps = base.clock.physics_steps if env_steps is None else env_steps
    return save_scripted_policy(
        ObservationOrder(policy, names),
        observation,
        path,
        behavior=base.setup.behavior.name,
        config=to_dict(base.setup.config),
        env_steps=steps,
        learner=learner,
        artifacts=base.setup.behavior.artifacts().policy_artifacts(),
    )


IDS = register_behaviors()
"""The ids this import registered: id -> behaviour name."""

__all__ = [
    "IDS",
    "devlearn_env",
    "env_id",
    "make_vec",
    "observation_names",
    "register_behaviors",
    "save_policy",
]
