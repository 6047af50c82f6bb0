"""A run whose body grows (issue #41): the schedule's age in every iteration, recorded in
checkpoints, and a run killed with kill -9 and resumed goes on at the right age."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import tiny_run

from devlearn.api.errors import UsageError
from devlearn.config.growth import parse_growth
from devlearn.training import train
from devlearn.training.checkpoint import load_checkpoint, resume_checkpoint

PER_ITERATION = 32  # 4 envs x 8 steps
TOTAL = 1_000_000
GROWTH = ("infant.growth=6->18", f"infant.growth_every={PER_ITERATION}")


def rows(run_dir: Path) -> list[dict]:
    return [json.loads(line) for line in (run_dir / "metrics.jsonl").read_text().splitlines()]


def run_until(args: list[str], done: Path) -> None:
    """Run tiny_run.py with ``args`` until ``done`` exists, then kill it with SIGKILL."""
    script = Path(tiny_run.__file__)
    proc = subprocess.Popen(
        [sys.executable, str(script), *args], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    )
    try:
        deadline = time.time() + 180
        while not done.exists():
            assert proc.poll() is None, proc.stderr.read().decode()  # type: ignore[union-attr]
            assert time.time() < deadline, f"{done} never came"
            time.sleep(0.05)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=10)
    finally:
        proc.kill()


def test_a_growing_run_resumed_after_kill_goes_on_at_its_age(tmp_path):
    out = tmp_path / "run"
    schedule = parse_growth("6->18", PER_ITERATION, TOTAL)
    assert schedule is not None

    def age(step: int) -> float:
        return schedule.age_at(step, TOTAL)

    run_until([str(out), str(TOTAL), *GROWTH], out / "checkpoint_160.pt")
    _, saved = resume_checkpoint(out)
    steps = saved["env_steps"]
    # a checkpoint records the body its last iteration trained with
    assert steps >= 160 and saved["age_months"] == age(steps - PER_ITERATION) > age(0) == 6.0

    run_until(["--resume", str(out)], out / f"checkpoint_{steps + 3 * PER_ITERATION}.pt")
    _, again = resume_checkpoint(out)
    assert again["env_steps"] > steps
    assert again["age_months"] == age(again["env_steps"] - PER_ITERATION)
    # every iteration, before and after the kill, ran at its piece's age: one piece per
    # iteration here, each a little older (a row's step is the count after its iteration).
    # The kill can land after an iteration's row and before its checkpoint: that row is past
    # the last checkpoint (a resume forgets it), so compare through the checkpoint's step.
    logged = rows(out)
    assert all(r["step"] <= again["env_steps"] + PER_ITERATION for r in logged)
    ages = {r["step"]: r["age_months"] for r in logged if r["step"] <= again["env_steps"]}
    assert sorted(ages) == list(range(PER_ITERATION, again["env_steps"] + 1, PER_ITERATION))
    assert all(a == age(step - PER_ITERATION) for step, a in ages.items())
    assert len(set(ages.values())) == len(ages)


def test_stages_of_growth_and_a_fixed_age(tmp_path, capsys):
    cfg = tiny_run.config(tmp_path / "grow", 6 * PER_ITERATION, "infant.growth=3,9,15")
    train(cfg, tiny_run.registry(), infant_factory=tiny_run.factory, progress=False)
    assert [r["age_months"] for r in rows(tmp_path / "grow")] == [3, 3, 9, 9, 15, 15]
    final = load_checkpoint(tmp_path / "grow" / "checkpoint_latest.pt")
    assert final["age_months"] == 15

    cfg = tiny_run.config(tmp_path / "fixed", 2 * PER_ITERATION, "infant.age_months=4.5")
    train(cfg, tiny_run.registry(), infant_factory=tiny_run.factory, progress=False)
    assert [r["age_months"] for r in rows(tmp_path / "fixed")] == [4.5, 4.5]
    # resumed with another age: its config's body, and a note saying so
    cfg = tiny_run.config(tmp_path / "fixed", 3 * PER_ITERATION, "infant.age_months=6")
    registry = tiny_run.registry()
    capsys.readouterr()
    train(cfg, registry, resume=tmp_path / "fixed", infant_factory=tiny_run.factory, progress=False)
    assert [r["age_months"] for r in rows(tmp_path / "fixed")] == [4.5, 4.5, 6.0]
    assert "the checkpoint's body was the body at 4.5 months; this run goes on with the body " in (
        capsys.readouterr().err
    )

    cfg = tiny_run.config(tmp_path / "default", PER_ITERATION)
    train(cfg, tiny_run.registry(), infant_factory=tiny_run.factory, progress=False)
    assert "age_months" not in rows(tmp_path / "default")[0]
    assert load_checkpoint(tmp_path / "default" / "checkpoint_latest.pt")["age_months"] is None


def test_one_age_per_curriculum_stage(tmp_path):
    stages = ("behavior.stage_steps=64", "infant.growth=stages:2,20")  # tiny: fixed, random
    cfg = tiny_run.config(tmp_path / "run", 4 * PER_ITERATION, *stages)
    train(cfg, tiny_run.registry(), infant_factory=tiny_run.factory, progress=False)
    assert [(r["stage"], r["age_months"]) for r in rows(tmp_path / "run")] == [
        ("fixed", 2.0),
        ("fixed", 2.0),
        ("random", 20.0),
        ("random", 20.0),
    ]
    cfg = tiny_run.config(tmp_path / "more", 64, "infant.growth=stages:1,2,3")
    with pytest.raises(UsageError, match=r"names 3 ages, but tiny's curriculum has 2 stage"):
        train(cfg, tiny_run.registry(), infant_factory=tiny_run.factory, progress=False)


def test_a_resume_never_moves_the_age_back_and_keeps_the_schedule(
    cli_with, refused, tmp_path, capsys
):
    # issue #55, fault 13: resumed with only --steps changed, the schedule was stretched over
    # the new total and the body went from 18 back to 14 months; a changed infant.growth was
    # taken silently
    from devlearn.testing.fake_infant import TinyBehavior

    cli = cli_with(TinyBehavior)
    out = tmp_path / "run"
    small = ["--envs", "4", "--workers", "0", "--set", "save_interval=1", "--set", GROWTH[1]]
    assert cli(["run", "tiny", "--steps", "128", "--out", str(out), *small,
                "--set", GROWTH[0]]) == 0  # fmt: skip
    assert [r["age_months"] for r in rows(out)] == [6.0, 10.0, 14.0, 18.0]
    config = (out / "config.json").read_text()
    changes = [
        ("infant.growth=6->24", "growth"),
        ("infant.growth=", "growth"),
        ("infant.growth_every=64", "growth_every"),
        ("infant.growth_steps=64", "growth_steps"),
    ]
    for change, key in changes:
        err = refused(cli, "run", "tiny", "--resume", str(out), "--steps", "256", "--set", change)
        assert f"run {out} grows by infant.{key}=" in err and "which a resumed run keeps" in err
        assert f"--from {out}/checkpoint_latest.pt" in err
    assert (out / "config.json").read_text() == config and len(rows(out)) == 4
    capsys.readouterr()
    assert cli(["run", "tiny", "--resume", str(out), "--steps", "256"]) == 0
    assert [r["age_months"] for r in rows(out)] == [6.0, 10.0, 14.0, 18.0, 18.0, 18.0, 18.0, 18.0]
    assert (
        f"devlearn: note: run {out} keeps its growth schedule over its first 128 steps "
        "(infant.growth_steps, recorded in config.json); its body stays at 18 months after them"
    ) in capsys.readouterr().err
    assert json.loads((out / "config.json").read_text())["infant"]["growth_steps"] == 128
    assert load_checkpoint(out / "checkpoint_latest.pt")["age_months"] == 18.0
    assert cli(["run", "tiny", "--resume", str(out), "--steps", "320"]) == 0  # kept on: no note
    assert rows(out)[-1]["age_months"] == 18.0 and "note" not in capsys.readouterr().err
