"""``devlearn run`` and ``devlearn eval``: the whole path, resume, and one-line errors."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "env"))

from tiny_behaviors import OtherBehavior  # noqa: E402

from devlearn.testing.fake_infant import TinyBehavior  # noqa: E402

SMALL = ["--envs", "2", "--seed", "1", "--set", "save_interval=1"]


@pytest.fixture
def cli(cli_with):
    """Run ``devlearn ...`` in process with the tiny behaviours installed and a fake infant."""
    return cli_with(TinyBehavior, OtherBehavior)


def test_run_then_eval(cli, tmp_path, capsys):
    out = tmp_path / "run"
    assert cli(["run", "tiny", "--steps", "64", "--out", str(out), *SMALL]) == 0
    printed = capsys.readouterr().out
    assert f"run directory: {out}" in printed
    assert "finished: 64 environment steps, 4 iterations" in printed  # see test_run_summary
    assert json.loads((out / "config.json").read_text())["num_envs"] == 2

    ckpt = out / "checkpoint_latest.pt"
    assert cli(["eval", "tiny", "--checkpoint", str(ckpt), "--episodes", "2", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["episodes"] == 2 and result["checkpoint_env_steps"] == 64
    assert (out / "eval" / "eval.json").exists() and (out / "eval" / "close.txt").exists()

    assert cli(["run", "tiny", "--resume", str(out), "--steps", "96"]) == 0
    assert "finished: 96 environment steps" in capsys.readouterr().out
    steps = [json.loads(line)["step"] for line in (out / "metrics.jsonl").read_text().splitlines()]
    assert steps == [16, 32, 48, 64, 80, 96]


def test_eval_video(cli, tmp_path, capsys):
    out = tmp_path / "run"
    assert cli(["run", "tiny", "--steps", "16", "--out", str(out), *SMALL]) == 0
    video = tmp_path / "episode.mp4"
    ckpt = str(out / "checkpoint_latest.pt")
    eval_dir = tmp_path / "eval"
    assert (
        cli(
            [
                "eval",
                "tiny",
                "--checkpoint",
                ckpt,
                "--episodes",
                "1",
                "--video",
                str(video),
                "--out",
                str(eval_dir),
            ]
        )
        == 0
    )
    assert video.stat().st_size > 0 and (eval_dir / "eval.json").exists()
    assert "close" in capsys.readouterr().out


def test_run_errors(cli, refused, tmp_path):
    assert "bad value 'lots' for total_steps" in refused(
        cli, "run", "tiny", "--steps", "lots"
    )
    assert "--envs must be at least 1" in refused(cli, "run", "tiny", "--envs", "0")
    assert "--device must be cpu, cuda or cuda:N" in refused(
        cli, "run", "tiny", "--device", "tpu"
    )
    err = refused(cli, "run", "tiny", "--set", "ppo.lr=1")
    assert "unknown config key 'ppo.lr'; did you mean 'ppo.learning_rate'?" in err
    assert "unknown behavior 'tinyy'" in refused(cli, "run", "tinyy")
    empty = tmp_path / "empty"
    empty.mkdir()
    assert "cannot read" in refused(cli, "run", "tiny", "--resume", str(empty))
    assert "does not exist" in refused(cli, "run", "tiny", "--resume", str(tmp_path / "x"))
    out = tmp_path / "run"
    assert cli(["run", "tiny", "--steps", "16", "--out", str(out), *SMALL]) == 0
    for ckpt in out.glob("checkpoint_*.pt"):
        ckpt.unlink()
    assert "no checkpoint in" in refused(cli, "run", "tiny", "--resume", str(out))
    assert "trains 'tiny', not 'other'" in refused(cli, "run", "other", "--resume", str(out))


def test_eval_errors(cli, refused, tmp_path):
    out = tmp_path / "run"
    assert cli(["run", "tiny", "--steps", "16", "--out", str(out), *SMALL]) == 0
    ckpt = out / "checkpoint_latest.pt"
    err = refused(cli, "eval", "other", "--checkpoint", str(ckpt))
    assert f"checkpoint {ckpt} was trained for 'tiny', not 'other'" in err
    truncated = tmp_path / "truncated.pt"
    truncated.write_bytes(ckpt.read_bytes()[:1000])
    err = refused(cli, "eval", "tiny", "--checkpoint", str(truncated))
    assert f"checkpoint {truncated} is corrupt or unreadable" in err
    missing = tmp_path / "missing.pt"
    assert "does not exist" in refused(cli, "eval", "tiny", "--checkpoint", str(missing))
    assert "--episodes must be at least 1" in refused(
        cli, "eval", "tiny", "--checkpoint", str(ckpt), "--episodes", "0"
    )


def test_sigterm_saves_a_checkpoint_and_restores_handlers(cli, tmp_path, monkeypatch):
    import os
    import signal

    from devlearn.training.checkpoint import load_checkpoint
    from devlearn.training.runner_metrics import MetricsLog

    record = MetricsLog.record

    def record_then_terminate(self, figures, *args, **kwargs):
        row = record(self, figures, *args, **kwargs)
        if figures.env_steps == 32:  # the scheduler's SIGTERM, mid-run
            os.kill(os.getpid(), signal.SIGTERM)
        return row

    monkeypatch.setattr(MetricsLog, "record", record_then_terminate)
    before = signal.getsignal(signal.SIGTERM)
    out = tmp_path / "run"
    small = ["--envs", "2", "--seed", "1", "--set", "save_interval=1000"]
    assert cli(["run", "tiny", "--steps", "100000", "--out", str(out), *small]) == 130
    assert load_checkpoint(out / "checkpoint_latest.pt")["env_steps"] == 32
    assert signal.getsignal(signal.SIGTERM) is before


def test_eval_prints_a_short_summary_led_by_the_headline(cli, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "run"
    assert cli(["run", "tiny", "--steps", "64", "--out", str(out), *SMALL]) == 0
    assert cli(["eval", "tiny", "--policy", "zero", "--episodes", "2"]) == 0  # eval_tiny_zero
    capsys.readouterr()
    assert cli(["eval", "tiny", "--checkpoint", str(out), "--episodes", "2"]) == 0
    printed = capsys.readouterr().out  # the baseline started elsewhere: said, not compared
    assert "  baselines none from rest starts; other starts: zero (random)" in printed
    args = ["--policy", "zero", "--episodes", "2", "--start", "rest", "--out", "eval_tiny_zero"]
    assert cli(["eval", "tiny", *args]) == 0
    capsys.readouterr()
    assert cli(["eval", "tiny", "--checkpoint", str(out), "--episodes", "2"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == f"tiny: {out / 'checkpoint_latest.pt'} (64 training steps)"
    assert lines[1].startswith("  2 episodes from rest starts, eval seed 0")
    assert lines[2].startswith("  headline  episode_close_mean = ")  # the per-episode headline
    assert lines[3].startswith("  baselines zero ") and "(same start)" in lines[3]
    assert any(line.startswith(f"  all figures: {out / 'eval' / 'eval.json'}") for line in lines)
    assert any(line.startswith("  policy    mean action at the bounds in ") for line in lines)
    assert len(lines) <= 8 and all(len(line) < 300 for line in lines)  # no raw dump
    assert cli(["eval", "tiny", "--checkpoint", str(out), "--episodes", "2", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["episodes"] == 2  # --json keeps everything
    err = "--compare nowhere: no readable eval.json there"
    assert cli(["eval", "tiny", "--checkpoint", str(out), "--compare", "nowhere"]) == 2
    assert err in capsys.readouterr().err


def test_a_signal_inside_an_env_step_is_taken_between_decisions(cli, tmp_path, monkeypatch):
    """SIGTERM that lands inside a step (a compiled kernel, in a real run) does not raise
    there: the step finishes, and the run stops at the next decision with a checkpoint."""
    import os
    import signal

    from devlearn.testing.fake_infant import FakeInfant
    from devlearn.training.checkpoint import load_checkpoint

    step = FakeInfant.step
    calls: list[int] = []
    finished: list[int] = []

    def step_with_a_signal_inside(self, action):
        calls.append(1)
        if len(calls) == 40 and not finished:  # 20 decisions of 2 envs: the second iteration
            os.kill(os.getpid(), signal.SIGTERM)  # mid-step, as inside a kernel
            finished.append(1)  # still running: the handler raised nothing here
        return step(self, action)

    monkeypatch.setattr(FakeInfant, "step", step_with_a_signal_inside)
    out = tmp_path / "run"
    small = ["--envs", "2", "--seed", "1", "--workers", "0", "--set", "save_interval=1000"]
    assert cli(["run", "tiny", "--steps", "100000", "--out", str(out), *small]) == 130
    assert finished == [1]
    assert load_checkpoint(out / "checkpoint_latest.pt")["env_steps"] == 32  # the last boundary


def test_the_summary_puts_every_criterion_of_the_headline_beside_it():
    """Hand regard: the paper's measure (the detector) first, ground-truth pixels beside it."""
    from devlearn.cli.evaluate import human_summary

    criterion = {"average": 0.5, "episode_average_mean": 0.5, "episode_average_ci_low": 0.4,
                 "episode_average_ci_high": 0.6}  # fmt: skip
    summary = {
        "behavior": "hand_regard", "policy": "zero", "start": "babybench", "episodes": 10,
        "average": 0.5, "episode_average_mean": 0.5, "episode_average_ci_low": 0.4,
        "episode_average_ci_high": 0.6, "protocol": {"headline": "detector", "seed": 0},
        "criteria": {"detector": criterion, "pixels": {**criterion, "episode_average_mean": 0.25}},
    }  # fmt: skip
    lines = human_summary(summary, "average", {}, None)
    assert lines[2] == "  headline  episode_average_mean = 0.5 [0.4, 0.6] (95% interval over episodes)"
    assert lines[3].startswith("  criteria  detector 0.5, pixels 0.25")


def test_asking_for_workers_never_slows_a_small_evaluation(cli, tmp_path, capsys):
    """Issue #55: ``--workers 2`` on 12 episodes started two workers and took twice as long as
    one process; a small job stays in one process whatever is asked, and says so."""
    out = tmp_path / "run"
    assert cli(["run", "tiny", "--steps", "16", "--out", str(out), *SMALL]) == 0
    ckpt = str(out / "checkpoint_latest.pt")
    capsys.readouterr()
    argv = ["eval", "tiny", "--checkpoint", ckpt, "--episodes", "12", "--workers", "2"]
    assert cli([*argv, "--out", str(tmp_path / "small"), "--json"]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["execution"]["workers"] == 0
    assert "note: --workers 2 for 12 episodes: played in this process" in captured.err
    from devlearn.evaluation.evaluate import paying_workers

    # one worker per 8 episodes, none where that leaves one; never more than asked
    assert [paying_workers(n, 4) for n in (12, 15, 16, 24, 40, 400)] == [0, 0, 2, 3, 4, 4]
    assert paying_workers(400, 0) == 0
