"""Environments: one BehaviorEnv per sub-environment, batched by DevVecEnv for rsl-rl."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from devlearn.env.behavior_env import BehaviorEnv
from devlearn.env.settings import EnvSettings
from devlearn.env.workers import EnvWorkerError

if TYPE_CHECKING:
    from devlearn.env.vec_env import DevVecEnv

__all__ = ["BehaviorEnv", "DevVecEnv", "EnvSettings", "EnvWorkerError"]


def __getattr__(name: str) -> Any:
    # DevVecEnv pulls in rsl-rl and tensordict (seconds of imports); worker processes, which
    # import this package for BehaviorEnv, never need it.
    if name == "DevVecEnv":
        from devlearn.env.vec_env import DevVecEnv

        return DevVecEnv
    raise AttributeError(f"module 'devlearn.env' has no attribute {name!r}")
