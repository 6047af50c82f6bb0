"""What a behaviour's environment looks like: observation shapes, actions, skin, timing."""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING, Any

import numpy as np

from devlearn.api.batching import EnvBatch
from devlearn.api.behavior import Behavior

if TYPE_CHECKING:
    from devlearn.env.behavior_env import InfantFactory


def describe_behavior(
    behavior: Behavior, infant_factory: InfantFactory | None = None, action_repeat: int = 1
) -> dict[str, Any]:
    """Build the behaviour's infant once and describe its environment.

    Args:
        behavior: A behaviour instance (its default config is fine).
        infant_factory: Optional ``(scene, senses, **episode.infant_options) -> Infant``
            replacement for tests.
        action_repeat: Physics steps per policy decision of the run described
            (``env.action_repeat``).

    Returns:
        JSON-ready dict with keys ``behavior``, ``description``, ``scene``, ``senses``,
        ``observations`` (name -> shape list), ``obs_groups``, ``action_dim``, ``touch_sensors``,
        ``skin_regions``, ``regions_per_side``, ``physics_timestep``, ``action_repeat``,
        ``decision_interval`` (seconds between the policy's decisions: the physics step times
        the action repeat), ``episode_steps`` (physics steps), ``reward_terms`` and
        ``curriculum``.
    """
    episode = behavior.episode()
    if infant_factory is None:
        from devlearn.infant import build_infant

        # The numpy references of the compiled senses: the same shapes, and describing compiles
        # nothing (no numba import, no kernel load: `devlearn info` starts in about a second).
        infant = build_infant(
            behavior.scene, senses=episode.senses, compiled=False, **episode.infant_options
        )
    else:
        infant = infant_factory(behavior.scene, episode.senses, **episode.infant_options)
    try:
        rng = np.random.default_rng(0)
        infant.reset(rng, random_pose=False)
        episode.hooks.on_episode_start(infant, rng)
        # Shapes only: warnings about what an unprepared behaviour would perceive or learn
        # (hand regard's uncalibrated detector) do not change them, so they are not shown.
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            one = EnvBatch([infant], [behavior])
            batch = behavior.observe(one, behavior.facts(one))
        observations = {name: np.asarray(array)[0] for name, array in batch.items()}
        body = infant.describe()
    finally:
        infant.close()
    curriculum = behavior.curriculum()
    return {
        "behavior": behavior.name,
        "description": behavior.about.description,
        "scene": behavior.scene,
        "senses": list(episode.senses),
        "observations": {k: list(np.shape(v)) for k, v in observations.items()},
        "obs_groups": behavior.network().obs_groups(list(observations)),
        "action_dim": int(body["action_dim"]),
        "touch_sensors": int(body["touch_sensors"]),
        "skin_regions": int(body["skin_regions"]),
        "regions_per_side": int(body["regions_per_side"]),
        "physics_timestep": float(body["physics_timestep"]),
        "action_repeat": int(action_repeat),
        "decision_interval": round(float(body["control_timestep"]) * action_repeat, 9),
        "episode_steps": int(body["episode_steps"]),
        "reward_terms": [term.name for term in behavior.reward_terms()],
        "curriculum": [
            {"name": s.name, "steps": s.steps, "options": s.options} for s in curriculum.stages
        ],
    }
