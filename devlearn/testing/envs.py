"""A behaviour's environments for tests, built and stepped exactly as training builds and steps
them (one implementation: the core's, re-exported), so that a plugin's tests play their
behaviour without reaching into ``devlearn.env``.

- :class:`BehaviorEnv` (``BehaviorEnv(behavior, seed, infant_factory=None, training=True,
  action_repeat=1, ...)``): one env; ``reset()``, ``step(action)``, ``set_stage(options)``.
- :func:`make_envs`: the envs of one worker (one copy of the behaviour each), sharing their
  batched reward terms; :func:`step_batch` advances them one decision together.
- :func:`term_values`: one physics step's value of every reward term (the one place term values
  are computed); :func:`share_batched_terms` shares the batched terms of hand-built envs.
- ``DevVecEnv`` (``devlearn.env.DevVecEnv``, loaded on first use: rsl-rl): the batch of envs the
  runner steps, in this process or in worker processes.
- :data:`EPISODE_RECORD`: the key of an ended episode's record in an env's ``info``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from devlearn.env.behavior_env import (
    EPISODE_RECORD,
    BehaviorEnv,
    share_batched_terms,
    step_batch,
    term_values,
)
from devlearn.env.workers import make_envs

if TYPE_CHECKING:
    from devlearn.env.vec_env import DevVecEnv

__all__ = [
    "EPISODE_RECORD",
    "BehaviorEnv",
    "DevVecEnv",
    "make_envs",
    "share_batched_terms",
    "step_batch",
    "term_values",
]


def __getattr__(name: str) -> Any:
    # DevVecEnv pulls in rsl-rl and tensordict: loaded only by the tests that step the batch
    if name == "DevVecEnv":
        from devlearn.env.vec_env import DevVecEnv

        return DevVecEnv
    raise AttributeError(f"module 'devlearn.testing.envs' has no attribute {name!r}")
