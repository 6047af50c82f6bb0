"""The batch's arrays (observations, actions, rewards, dones), in process or in shared memory."""

from __future__ import annotations

from multiprocessing import shared_memory
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from devlearn.env.behavior_env import BehaviorEnv


def env_spec(env: BehaviorEnv, obs: dict[str, np.ndarray]) -> dict[str, Any]:
    """Describe an env's batch layout: observation shapes/dtypes, reward-term names, action
    size, episode length."""
    return {
        "obs": {k: (tuple(np.shape(v)), _buffer_dtype(v)) for k, v in obs.items()},
        "terms": [term.name for term in env.terms],
        "action_dim": env.action_dim,
        "episode_steps": env.episode_steps,
        "step_dt": env.step_dt,
    }


def _buffer_dtype(value: np.ndarray) -> str:
    """uint8 stays uint8 (images); everything else is stored as float32."""
    return "uint8" if np.asarray(value).dtype == np.uint8 else "float32"


class EnvBuffers:
    """The batch's arrays: ``obs/<name>`` (N, *shape), ``actions`` (N, A) float32,
    ``rewards`` (N,) float32, ``dones`` and ``time_outs`` (N,) bool, ``term_rewards`` (N, T)
    float64 (each reward term's share of the last decision) and ``final/<name>`` (N, *shape)
    (the last observation of an env's episode, in the rows of envs whose episode just ended).

    With ``shared=True`` every array lives in a ``multiprocessing.shared_memory`` block that
    worker processes attach to by name, so steps move no array through pipes.
    """

    def __init__(self, spec: dict[str, Any], num_envs: int, shared: bool) -> None:
        layout = {f"obs/{k}": ((num_envs, *shape), dt) for k, (shape, dt) in spec["obs"].items()}
        layout["actions"] = ((num_envs, spec["action_dim"]), "float32")
        layout["rewards"] = ((num_envs,), "float32")
        layout["dones"] = ((num_envs,), "bool")
        layout["time_outs"] = ((num_envs,), "bool")
        layout["term_rewards"] = ((num_envs, len(spec["terms"])), "float64")
        for k, (shape, dt) in spec["obs"].items():
            layout[f"final/{k}"] = ((num_envs, *shape), dt)
        self.layout = layout
        self.blocks: list[shared_memory.SharedMemory] = []
        self.arrays: dict[str, np.ndarray] = {}
        for key, (shape, dtype) in layout.items():
            if shared:
                nbytes = max(int(np.prod(shape)) * np.dtype(dtype).itemsize, 1)
                block = shared_memory.SharedMemory(create=True, size=nbytes)
                self.blocks.append(block)
                self.arrays[key] = np.ndarray(shape, dtype=dtype, buffer=block.buf)
                self.arrays[key].fill(0)
            else:
                self.arrays[key] = np.zeros(shape, dtype=dtype)

    def handle(self) -> dict[str, Any]:
        """Return what a worker needs to attach: block names and the layout (picklable)."""
        return {"names": [b.name for b in self.blocks], "layout": self.layout}

    def close(self, unlink: bool = True) -> None:
        """Release (and by default unlink) the shared-memory blocks."""
        self.arrays = {}
        for block in self.blocks:
            block.close()
            if unlink:
                block.unlink()
        self.blocks = []


def attach(handle: dict[str, Any]) -> tuple[dict[str, np.ndarray], list]:
    """In a worker: the batch arrays of :meth:`EnvBuffers.handle`, and their blocks (to close)."""
    blocks = [shared_memory.SharedMemory(name=n) for n in handle["names"]]
    arrays = {
        key: np.ndarray(shape, dtype=dtype, buffer=block.buf)
        for (key, (shape, dtype)), block in zip(handle["layout"].items(), blocks)
    }
    return arrays, blocks


def write_obs(
    arrays: dict[str, np.ndarray], index: int, obs: dict[str, np.ndarray], prefix: str = "obs/"
) -> None:
    """Copy one env's observations into row ``index`` of the batch arrays (``prefix``
    ``final/``: of its episode's last observations)."""
    for key, value in obs.items():
        arrays[f"{prefix}{key}"][index] = value
