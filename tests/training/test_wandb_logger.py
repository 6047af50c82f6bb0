"""``devlearn run --logger wandb``: rsl-rl's W&B writer, in W&B's offline mode (no network)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "env"))

from devlearn.api.errors import UsageError  # noqa: E402
from devlearn.config.run_config import RunConfig  # noqa: E402
from devlearn.testing.fake_infant import TinyBehavior  # noqa: E402
from devlearn.training.loggers import logger_config  # noqa: E402


@pytest.fixture
def cli(cli_with):
    return cli_with(TinyBehavior)


def test_logger_config():
    assert logger_config(RunConfig()) == "tensorboard"
    wandb = logger_config(RunConfig(logger="wandb", wandb_project="infant"))
    assert wandb == {
        "class_name": "devlearn.training.loggers:RunDirWandbWriter",
        "project_name": "infant",
    }
    with pytest.raises(UsageError, match="unknown logger 'neptune'; valid loggers: tensorboard"):
        logger_config(RunConfig(logger="neptune"))


@pytest.mark.slow
def test_wandb_offline_run_logs_scalars_and_config_into_the_run_dir(cli, tmp_path, monkeypatch):
    pytest.importorskip("wandb")
    monkeypatch.setenv("WANDB_MODE", "offline")
    monkeypatch.setenv("WANDB_SILENT", "true")
    monkeypatch.delenv("WANDB_DIR", raising=False)
    out = tmp_path / "run"
    args = ["run", "tiny", "--steps", "64", "--envs", "2", "--workers", "0", "--out", str(out)]
    assert cli([*args, "--logger", "wandb", "--set", "wandb_project=infant-test"]) == 0
    assert "WANDB_DIR" not in os.environ
    runs = list((out / "wandb").glob("offline-run-*/run-*.wandb"))
    assert len(runs) == 1
    data = runs[0].read_bytes()
    for key in (b"Loss/value", b"Loss/surrogate", b"train_cfg", b"env_cfg", b"infant-test"):
        assert key in data, key
    assert list(out.glob("events.out.tfevents.*"))  # the W&B writer also writes TensorBoard
    assert (out / "checkpoint_latest.pt").exists()
