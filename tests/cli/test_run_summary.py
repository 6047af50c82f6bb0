"""What a finished ``devlearn run`` prints, and resuming a run that is already finished."""

from __future__ import annotations

import functools
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "env"))

from fake_infant import TinyBehavior, fake_infant_factory  # noqa: E402

import devlearn.plugins  # noqa: E402
from devlearn.cli import main  # noqa: E402
from devlearn.cli.summary import headline  # noqa: E402
from devlearn.testing import registry_for  # noqa: E402

SMALL = ["--envs", "2", "--seed", "1", "--workers", "0", "--set", "save_interval=1"]


@pytest.fixture
def cli(monkeypatch):
    """``devlearn ...`` in process with the tiny behaviour and a fake infant."""
    registry = registry_for(TinyBehavior)
    monkeypatch.setattr(devlearn.plugins, "PluginRegistry", lambda *a, **k: registry)
    fake = functools.partial(fake_infant_factory, episode_steps=10)
    monkeypatch.setattr("devlearn.env.behavior_env.build_default_infant", fake)
    return main


def test_finished_run_prints_where_how_far_and_what_next(cli, tmp_path, capsys):
    out = tmp_path / "run"
    assert cli(["run", "tiny", "--steps", "64", "--out", str(out), *SMALL]) == 0
    printed = capsys.readouterr().out
    assert "{" not in printed  # no JSON dump of the last iteration
    assert "finished: 64 environment steps, 4 iterations" in printed
    assert f"checkpoint  {out / 'checkpoint_latest.pt'}" in printed
    assert (
        f"logs        {out / 'metrics.jsonl'}, TensorBoard: tensorboard --logdir {out}" in printed
    )
    assert "metrics/close" in printed and "at the start (step 16)" in printed
    assert f"devlearn eval tiny --checkpoint {out / 'checkpoint_latest.pt'}" in printed
    assert f"devlearn curve {out}" in printed
    assert f"devlearn run tiny --resume {out} --steps 128" in printed


def test_resuming_a_finished_run_says_so_and_writes_nothing(cli, tmp_path, capsys):
    out = tmp_path / "run"
    assert cli(["run", "tiny", "--steps", "32", "--out", str(out), *SMALL]) == 0
    capsys.readouterr()
    before = {p: p.stat().st_mtime_ns for p in out.rglob("*")}
    assert cli(["run", "tiny", "--resume", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "already finished (32 of 32 steps); nothing was written" in printed
    assert f"--resume {out} --steps 64" in printed
    assert {p: p.stat().st_mtime_ns for p in out.rglob("*")} == before  # no new TensorBoard file


def test_headline_prefers_the_behaviour_metric_then_mean_reward():
    rows = [
        {"mean_reward": None},
        {"mean_reward": 1.0, "metrics/x": 2.0},
        {"mean_reward": 3.0, "metrics/x": 5.0},
    ]
    assert headline(rows, "x") == ("metrics/x", 2.0, 5.0)
    assert headline(rows, "") == ("mean_reward", 1.0, 3.0)
    assert headline([], "x") == ("mean_reward", None, None)


def test_progress_bar_stops_at_its_total_and_draws_the_end_once(cli, tmp_path, capsys):
    # 70 steps at 16 per iteration: the last iteration overshoots to 80.
    assert cli(["run", "tiny", "--steps", "70", "--out", str(tmp_path / "r"), *SMALL]) == 0
    lines = [line.strip() for line in capsys.readouterr().err.replace("\r", "\n").splitlines()]
    bars = [line for line in lines if "step/s" in line]
    assert bars and "70.0/70.0" in bars[-1] and bars[-1].startswith("100%")
    assert not any("80.0" in line for line in bars)
    assert sum(line.startswith("100%") for line in bars) == 1


def test_the_suggested_curve_works_before_any_episode_ended(tmp_path):
    import argparse
    import json

    from devlearn.cli import curve

    rows = [
        {"step": 256 * (i + 1), "mean_step_reward": 0.1 * i, "mean_reward": None} for i in range(3)
    ]
    (tmp_path / "metrics.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    args = {"run_dirs": [tmp_path], "metric": None, "smooth": 3, "out": None, "vs": None}
    assert curve.run(argparse.Namespace(**args), None) == 0  # plots mean_step_reward
    assert (tmp_path / "learning_curve.png").exists()
