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
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import gymnasium

if TYPE_CHECKING:
    from gymnasium.vector import VectorEnv

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


IDS = register_behaviors()
"""The ids this import registered: id -> behaviour name."""

__all__ = ["IDS", "env_id", "make_vec", "register_behaviors"]
