"""Environments: one BehaviorEnv per sub-environment, batched by DevVecEnv for rsl-rl."""

from __future__ import annotations

from devlearn.env.behavior_env import BehaviorEnv
from devlearn.env.vec_env import DevVecEnv
from devlearn.env.workers import EnvWorkerError

__all__ = ["BehaviorEnv", "DevVecEnv", "EnvWorkerError"]
