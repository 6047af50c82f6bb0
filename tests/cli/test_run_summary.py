"""What a finished ``devlearn run`` prints, and resuming a run that is already finished."""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "env"))

from devlearn.cli.summary import headline  # noqa: E402
from devlearn.testing.fake_infant import TinyBehavior  # noqa: E402

SMALL = ["--envs", "2", "--seed", "1", "--workers", "0", "--set", "save_interval=1"]


@pytest.fixture
def cli(cli_with):
    """``devlearn ...`` in process with the tiny behaviour and a fake infant."""
    return cli_with(TinyBehavior)


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
    assert "  episode_close_mean  " in printed and "at the start (step 16)" in printed
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
    assert headline(rows, "x") == ("metrics/x", 2.0, 5.0)  # a run from before issue #55
    rows[2]["metrics/episode_x_mean"] = 5.0
    assert headline(rows, "x") == ("metrics/episode_x_mean", 5.0, 5.0)
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


def test_a_run_without_finished_episodes_says_why(cli, tmp_path, capsys):
    out = tmp_path / "run"  # 2 envs x 8 steps: the 10-step episodes never end
    assert cli(["run", "tiny", "--steps", "16", "--out", str(out), *SMALL]) == 0
    printed = capsys.readouterr().out
    assert (
        "- (no episode finished: each of the 2 environments ran 8 steps, less than one episode"
        in printed
    )


class PaperTiny(TinyBehavior):
    """The tiny behaviour with a preset that sets a full run's budget."""

    name = "tiny"

    about = dataclasses.replace(
        TinyBehavior.about, presets={"paper": {"total_steps": 320}, "other": {"seed": 3}}
    )


def test_the_summary_puts_the_run_beside_baselines_and_its_budget(
    cli_with, tmp_path, monkeypatch, capsys
):
    cli = cli_with(PaperTiny)
    monkeypatch.chdir(tmp_path)
    baseline = tmp_path / "eval_tiny_random"
    baseline.mkdir()
    summary = {"close": 0.25, "episode_close_mean": 0.125, "policy": "random"}
    (baseline / "eval.json").write_text(json.dumps(summary))
    assert cli(["run", "tiny", "--steps", "64", "--out", "run", *SMALL]) == 0
    printed = capsys.readouterr().out
    assert (
        "budget      64 steps, 20% of a full run (320, --preset paper): a demonstration" in printed
    )
    assert (
        "baselines   episode_close_mean under the evaluation protocol: random 0.125 "
        "(eval_tiny_random)" in printed  # the per-episode figure beside the run's, not the union
    )
    assert "devlearn eval tiny --policy zero --episodes 100   # baseline" in printed
    assert "devlearn eval tiny --policy random" not in printed  # already there
    assert "devlearn report run/eval eval_tiny_random eval_tiny_zero" in printed
    assert cli(["run", "tiny", "--steps", "320", "--out", "full", *SMALL]) == 0
    assert "budget " not in capsys.readouterr().out  # a full run is no demonstration


def test_the_summary_names_every_stage_the_run_went_through(cli, tmp_path, capsys):
    out = tmp_path / "run"
    argv = ["run", "tiny", "--steps", "64", "--out", str(out), "--set", "behavior.stage_steps=32"]
    assert cli([*argv, *SMALL]) == 0
    printed = capsys.readouterr().out
    assert "stages      fixed (logged from step 16) -> random (logged from step 48)" in printed


def test_one_headline_from_training_to_evaluation(cli, tmp_path, capsys):
    """Issue #55: the progress bar, the run summary, metrics.jsonl, ``devlearn curve`` and
    ``devlearn eval`` headline the behaviour's per-episode mean under one name."""
    import json

    from devlearn.cli import curve
    from devlearn.testing import registry_for

    out = tmp_path / "run"
    assert cli(["run", "tiny", "--steps", "64", "--out", str(out), *SMALL]) == 0
    captured = capsys.readouterr()
    rows = [json.loads(line) for line in (out / "metrics.jsonl").read_text().splitlines()]
    logged = [r for r in rows if "metrics/episode_close_mean" in r]
    assert logged and all(r["metrics/episode_close_mean"] == r["metrics/close"] for r in logged)
    assert "episode_close_mean=" in captured.err.replace("\r", "\n")  # the progress bar
    assert "  episode_close_mean  " in captured.out  # the summary
    assert curve.run_headline(out, registry_for(TinyBehavior)) == "metrics/episode_close_mean"
    assert cli(["eval", "tiny", "--checkpoint", str(out), "--episodes", "2", "--out",
                str(tmp_path / "ev")]) == 0  # fmt: skip
    assert "headline  episode_close_mean = " in capsys.readouterr().out


def test_the_baseline_commands_carry_the_runs_calibration(tmp_path):
    """Hand regard's baselines were suggested without the detector the run calibrated, so
    their ``detector`` figures were 0 whatever they did: the summary's baseline commands pass
    every behaviour-config file the run made in its folder, and nothing else."""
    import dataclasses
    from types import SimpleNamespace

    from devlearn.cli.summary import run_calibration, run_summary

    run = tmp_path / "run"
    run.mkdir()
    (run / "hand_detector.json").write_text("{}")
    (tmp_path / "elsewhere.json").write_text("{}")

    @dataclasses.dataclass
    class Config:
        detector_file: str = str(run / "hand_detector.json")
        prior_file: str = str(tmp_path / "elsewhere.json")  # not the run's: left out
        missing_file: str = str(run / "not_made.json")  # named, never made: left out
        scene: str = "sitting"
        steps: int = 3

    found = run_calibration(Config(), run)
    assert found == {"behavior.detector_file": str(run / "hand_detector.json")}
    assert run_calibration(None, run) == {}
    result = SimpleNamespace(run_dir=run, last={}, warnings=[], env_steps=100, iterations=1)
    text = run_summary(result, "tiny", "close", 100, behavior_config=Config())
    baselines = [line for line in text.splitlines() if "--policy" in line]
    assert len(baselines) == 2
    for line in baselines:
        assert f"--set behavior.detector_file={run / 'hand_detector.json'}" in line
        assert "this run's calibration" in line
    plain = run_summary(result, "tiny", "close", 100)
    assert all("--set" not in line for line in plain.splitlines() if "--policy" in line)
