"""Branching runs: stage-switch checkpoints and ``devlearn run --from CHECKPOINT``."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
import tiny_run
import torch

from devlearn.api.errors import UsageError
from devlearn.config.resolve import RunRequest, load_run_config, resolve_config
from devlearn.config.values import apply_overrides
from devlearn.training import train
from devlearn.training.checkpoint import checkpoint_config, load_checkpoint


def config_from_checkpoint(path: Path, behavior: str):
    """The config ``devlearn run BEHAVIOR --from PATH`` starts from, before its options."""
    request = RunRequest(behavior, start_from=str(path))
    return resolve_config(request, tiny_run.registry(), checkpoint_config)


def rows(run_dir: Path) -> list[dict]:
    return [json.loads(line) for line in (run_dir / "metrics.jsonl").read_text().splitlines()]


def run(cfg, **kwargs):
    return train(cfg, tiny_run.registry(), infant_factory=tiny_run.factory, progress=False, **kwargs)


def test_a_checkpoint_is_kept_where_the_curriculum_stage_switches(tmp_path):
    """Stage 1 lasts 40 steps: the boundary at 64 steps (32 per iteration) is the last of the
    fixed stage, kept as checkpoint_64.pt although save_interval keeps none there."""
    cfg = tiny_run.config(tmp_path / "r", 96, "behavior.stage_steps=40", save_interval=100)
    run(cfg)
    names = sorted(p.name for p in (tmp_path / "r").glob("checkpoint_*.pt"))
    assert names == ["checkpoint_64.pt", "checkpoint_96.pt", "checkpoint_latest.pt"]
    state = load_checkpoint(tmp_path / "r/checkpoint_64.pt")
    assert state["curriculum"]["index"] == 0  # the next iteration is the first of stage 2


def test_a_run_from_a_checkpoint_continues_it_in_a_new_folder(tmp_path):
    """Unchanged, a run from A's checkpoint_64.pt equals A resumed from there: weights,
    optimiser, env state (the lifetime counters) and step counts are carried over."""
    source = tmp_path / "a"
    run(tiny_run.config(source, 64, "behavior.stage_steps=40"))
    resumed = tmp_path / "a_resumed"
    shutil.copytree(source, resumed)
    cfg = load_run_config(resumed, tiny_run.registry())
    cfg.total_steps = 96
    run(cfg, resume=resumed)
    before = sorted(p.name for p in source.iterdir())

    cfg = config_from_checkpoint(source / "checkpoint_64.pt", "tiny")
    cfg.out_dir, cfg.total_steps = str(tmp_path / "b"), 96
    result = run(cfg, start_from=source / "checkpoint_64.pt")
    assert (result.env_steps, result.iterations) == (96, 3)
    assert sorted(p.name for p in source.iterdir()) == before  # the source run is untouched
    b = load_checkpoint(tmp_path / "b/checkpoint_latest.pt")
    a = load_checkpoint(resumed / "checkpoint_latest.pt")
    for key in a["actor_state_dict"]:
        torch.testing.assert_close(b["actor_state_dict"][key], a["actor_state_dict"][key])
    assert b["env"] == a["env"]
    assert [r["step"] for r in rows(tmp_path / "b")] == [32, 64, 96]  # A's rows, then its own
    saved = json.loads((tmp_path / "b/config.json").read_text())
    assert saved["start_from"] == str(source / "checkpoint_64.pt")


def test_a_run_from_a_checkpoint_takes_a_changed_behaviour_config(tmp_path):
    """The ablation's branch: from the two-stage run's switch checkpoint, a one-stage run
    (here: a stage 1 that lasts longer) keeps the fixed stage where the source switched."""
    source = tmp_path / "a"
    run(tiny_run.config(source, 96, "behavior.stage_steps=40"))
    assert [r["stage"] for r in rows(source)] == ["fixed", "fixed", "random"]
    cfg = config_from_checkpoint(source / "checkpoint_64.pt", "tiny")
    apply_overrides(cfg, ["behavior.stage_steps=1000"])
    cfg.out_dir, cfg.total_steps = str(tmp_path / "b"), 96
    run(cfg, start_from=source / "checkpoint_64.pt")
    assert [r["stage"] for r in rows(tmp_path / "b")] == ["fixed", "fixed", "fixed"]


def test_from_refuses_what_cannot_continue(tmp_path):
    source = tmp_path / "a"
    run(tiny_run.config(source, 32))
    with pytest.raises(UsageError, match="trained for 'tiny', not 'other'"):
        config_from_checkpoint(source / "checkpoint_latest.pt", "other")
    cfg = config_from_checkpoint(source / "checkpoint_latest.pt", "tiny")
    cfg.out_dir, cfg.num_envs = str(tmp_path / "b"), 2
    with pytest.raises(UsageError, match="resume with --envs 4"):
        run(cfg, start_from=source / "checkpoint_latest.pt")
    cfg.num_envs, cfg.out_dir = 4, str(source)
    with pytest.raises(UsageError, match="already holds a run"):
        run(cfg, start_from=source / "checkpoint_latest.pt")
