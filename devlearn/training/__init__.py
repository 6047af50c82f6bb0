"""Training: run config, networks, the PPO runner, train() and evaluate()."""

from __future__ import annotations

from devlearn.training.config import (
    PPOConfig,
    RunConfig,
    default_config,
    from_dict,
    to_dict,
    to_rsl_rl,
)
from devlearn.training.config_values import apply_overrides
from devlearn.training.evaluate import evaluate
from devlearn.training.train import TrainResult, train

__all__ = [
    "PPOConfig",
    "RunConfig",
    "TrainResult",
    "apply_overrides",
    "default_config",
    "evaluate",
    "from_dict",
    "to_dict",
    "to_rsl_rl",
    "train",
]
