"""Stable-Baselines3's VecEnv over a Gymnasium vector env that autoresets in the same step
(``AutoresetMode.SAME_STEP``, as devlearn's vector env does), so SB3 trains on devlearn's own
worker pool instead of its DummyVecEnv or SubprocVecEnv."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium
import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from stable_baselines3.common.vec_env.base_vec_env import (
    VecEnv,
    VecEnvIndices,
    VecEnvObs,
    VecEnvStepReturn,
)

MOVED = ("final_obs", "final_info")
"""Gymnasium's end-of-episode keys, which SB3 reads as ``terminal_observation`` and the info."""


class GymnasiumVecEnv(VecEnv):
    """SB3's vectorised-env API over ``envs``.

    SB3 wants what a same-step autoreset gives: on the step that ends an env's episode its
    row holds the next episode's first observation, and its info the episode's last one
    (``terminal_observation``, which PPO bootstraps from when ``TimeLimit.truncated``).
    Gymnasium's info (a dict of arrays with ``_key`` masks) becomes SB3's list of per-env dicts;
    ``final_info``'s keys (devlearn's ``episode/...``) join the ended env's dict.

    Args:
        envs: A Gymnasium vector env with ``metadata["autoreset_mode"]`` ``SAME_STEP``.
    Raises:
        ValueError: Another autoreset mode (SB3 would bootstrap from the wrong observation).
    """

    def __init__(self, envs: VectorEnv) -> None:
        mode = envs.metadata.get("autoreset_mode")
        if mode != AutoresetMode.SAME_STEP:
            raise ValueError(f"SB3 needs same-step autoreset; this vector env has {mode!r}")
        self.envs = envs
        self._actions = np.zeros(0)
        super().__init__(envs.num_envs, envs.single_observation_space, envs.single_action_space)

    def reset(self) -> VecEnvObs:
        # SB3's seed(s) sets env i's seed to s + i, as Gymnasium's vector reset(seed=s) does
        obs, info = self.envs.reset(seed=self._seeds[0])
        self._reset_seeds()
        self.reset_infos = self._per_env(info)
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self) -> VecEnvStepReturn:
        obs, rewards, terminated, truncated, info = self.envs.step(self._actions)
        dones = np.logical_or(terminated, truncated)
        infos = self._per_env(info)
        finals = info.get("final_info", {})
        for i in np.flatnonzero(dones):
            infos[i]["terminal_observation"] = info["final_obs"][i]
            infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
            infos[i].update(self._row(finals, int(i)))
        return obs, np.asarray(rewards, dtype=np.float32), dones, infos

    def _per_env(self, info: dict[str, Any]) -> list[dict[str, Any]]:
        """Gymnasium's dict of arrays as one dict per env (the keys its mask gives it)."""
        shared = {k: v for k, v in info.items() if k.removeprefix("_") not in MOVED}
        return [self._row(shared, i) for i in range(self.num_envs)]

    @staticmethod
    def _row(info: dict[str, Any], i: int) -> dict[str, Any]:
        """Env ``i``'s entries of a Gymnasium info (those its ``_key`` mask marks)."""
        row = {}
        for key, value in info.items():
            mask = info.get(f"_{key}")
            if not key.startswith("_") and (mask is None or mask[i]):
                row[key] = value[i]
        return row

    def close(self) -> None:
        self.envs.close()

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        return [getattr(self.envs, attr_name)] * len(list(self._get_indices(indices)))

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        setattr(self.envs, attr_name, value)

    def env_method(
        self,
        method_name: str,
        *method_args: Any,
        indices: VecEnvIndices = None,
        **method_kwargs: Any,
    ) -> list[Any]:
        result = getattr(self.envs, method_name)(*method_args, **method_kwargs)
        return [result] * len(list(self._get_indices(indices)))

    def env_is_wrapped(
        self, wrapper_class: type[gymnasium.Wrapper], indices: VecEnvIndices = None
    ) -> list[bool]:
        return [False] * len(list(self._get_indices(indices)))

    def get_images(self) -> Sequence[np.ndarray | None]:
        return [None] * self.num_envs
