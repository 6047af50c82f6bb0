"""Where a run's metrics go: TensorBoard, or also Weights & Biases through rsl-rl's writer."""

from __future__ import annotations

import importlib.util
import os
from typing import Any

from rsl_rl.utils.wandb_log_writer import WandbLogWriter  # imports without wandb installed

from devlearn.api.errors import UsageError

LOGGERS = ("tensorboard", "wandb")
"""Values of ``RunConfig.logger``."""


def logger_config(cfg: Any) -> str | dict[str, Any]:
    """rsl-rl's ``train_cfg["logger"]`` for ``cfg.logger``.

    ``wandb`` uses rsl-rl's own ``WandbLogWriter`` (it also writes the TensorBoard files) with
    project ``cfg.wandb_project``; W&B keeps its files in the run directory unless
    ``WANDB_DIR`` says otherwise, and ``WANDB_MODE=offline`` keeps everything local (upload
    later with ``wandb sync``).

    Raises:
        UsageError: An unknown logger, or ``wandb`` without the wandb package installed.
    """
    if cfg.logger not in LOGGERS:
        raise UsageError(f"unknown logger '{cfg.logger}'; valid loggers: {', '.join(LOGGERS)}")
    if cfg.logger == "tensorboard":
        return "tensorboard"
    if importlib.util.find_spec("wandb") is None:
        raise UsageError(
            "--logger wandb needs the wandb package: pip install 'devlearn[wandb]' "
            "(WANDB_MODE=offline logs without an account)"
        )
    return {
        "class_name": "devlearn.training.loggers:RunDirWandbWriter",
        "project_name": cfg.wandb_project,
    }


class RunDirWandbWriter(WandbLogWriter):
    """rsl-rl's W&B writer, keeping W&B's files in the run directory (unless ``WANDB_DIR``)."""

    def __init__(self, log_dir: str, project_name: str) -> None:
        before = os.environ.get("WANDB_DIR")
        os.environ["WANDB_DIR"] = before or str(log_dir)
        try:
            super().__init__(log_dir, project_name)
        finally:  # leave the process environment as it was
            if before is None:
                os.environ.pop("WANDB_DIR", None)
