"""train(): repeatability, curriculum, metrics, checkpoints, interrupt and resume after kill -9."""

from __future__ import annotations

import functools
import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import tiny_run
import torch

from devlearn.api.errors import UsageError
from devlearn.testing.fake_infant import fake_infant_factory
from devlearn.training import train
from devlearn.training.checkpoint import load_checkpoint, resume_checkpoint, save_atomic

PER_ITERATION = 32  # 4 envs x 8 steps


def rows(run_dir: Path) -> list[dict]:
    return [json.loads(line) for line in (run_dir / "metrics.jsonl").read_text().splitlines()]


def run(out: Path, steps: int, *overrides: str, **top):
    cfg = tiny_run.config(out, steps, *overrides, **top)
    return train(cfg, tiny_run.registry(), infant_factory=tiny_run.factory, progress=False)


def test_same_seed_same_run_different_seed_different(tmp_path):
    a = run(tmp_path / "a", 64, seed=3)
    b = run(tmp_path / "b", 64, seed=3)
    c = run(tmp_path / "c", 64, seed=4)
    drop = {"steps_per_s", "collect_s", "update_s"}  # wall-clock timings
    ra = [{k: v for k, v in r.items() if k not in drop} for r in rows(a.run_dir)]
    rb = [{k: v for k, v in r.items() if k not in drop} for r in rows(b.run_dir)]
    rc = [{k: v for k, v in r.items() if k not in drop} for r in rows(c.run_dir)]
    assert ra == rb and ra != rc
    pa = load_checkpoint(a.run_dir / "checkpoint_latest.pt")["actor_state_dict"]
    pb = load_checkpoint(b.run_dir / "checkpoint_latest.pt")["actor_state_dict"]
    for key in pa:
        torch.testing.assert_close(pa[key], pb[key], rtol=0, atol=0)


def test_metrics_curriculum_and_checkpoints(tmp_path):
    result = run(tmp_path / "r", 160, "behavior.stage_steps=64", save_interval=2)
    assert (result.env_steps, result.iterations) == (160, 5)
    lines = rows(result.run_dir)
    assert [r["step"] for r in lines] == [32, 64, 96, 128, 160]
    assert [r["iteration"] for r in lines] == [0, 1, 2, 3, 4]
    # the stage is chosen before each iteration from the steps done so far
    assert [r["stage"] for r in lines] == ["fixed", "fixed", "random", "random", "random"]
    for key in ("mean_reward", "reward/reach", "reward/counter", "metrics/close", "steps_per_s"):
        assert key in lines[-1]
    assert lines[-1]["mean_reward"] == pytest.approx(lines[-1]["reward/reach"])
    names = sorted(p.name for p in result.run_dir.glob("checkpoint_*.pt"))
    assert names == [
        "checkpoint_128.pt",
        "checkpoint_160.pt",
        "checkpoint_64.pt",
        "checkpoint_latest.pt",
    ]
    state = load_checkpoint(result.run_dir / "checkpoint_latest.pt")
    assert state["behavior"] == "tiny" and state["env_steps"] == 160 and state["iteration"] == 5
    assert state["curriculum"]["index"] == 1
    envs = state["env"]["ranks"][0]["envs"]
    assert [e["stage"] for e in envs] == [{"random_pose": True}] * 4
    assert [e["terms"]["counter"]["count"] for e in envs] == [40] * 4
    assert json.loads((result.run_dir / "config.json").read_text())["behavior"]["stage_steps"] == 64
    assert list(result.run_dir.glob("events.out.tfevents.*"))


def test_interrupt_saves_a_checkpoint(tmp_path):
    cfg = tiny_run.config(tmp_path / "r", 10_000, save_interval=1000)
    interrupting = functools.partial(fake_infant_factory, episode_steps=10, interrupt_after=70)
    with pytest.raises(KeyboardInterrupt):
        train(cfg, tiny_run.registry(), infant_factory=interrupting, progress=False)
    state = load_checkpoint(tmp_path / "r" / "checkpoint_latest.pt")
    # each infant steps 8 times per iteration: 8 iterations complete, the 9th is interrupted
    assert state["env_steps"] == 8 * PER_ITERATION
    # lifetime memory is that of the last complete iteration, not of the rollout thrown away
    assert [e["terms"]["counter"]["count"] for e in state["env"]["ranks"][0]["envs"]] == [64] * 4


def test_resume_after_kill(tmp_path):
    out = tmp_path / "run"
    script = Path(tiny_run.__file__)
    proc = subprocess.Popen(
        [sys.executable, str(script), str(out), "1000000", "behavior.stage_steps=96"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    try:
        deadline = time.time() + 120
        while time.time() < deadline:
            if (out / "checkpoint_160.pt").exists():
                break
            assert proc.poll() is None, proc.stderr.read().decode()
            time.sleep(0.05)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=10)
    finally:
        proc.kill()
    path, saved = resume_checkpoint(out)
    steps = saved["env_steps"]
    # the kill may land between a periodic checkpoint and checkpoint_latest.pt: resume takes
    # whichever is furthest along
    assert path.name in ("checkpoint_latest.pt", f"checkpoint_{steps}.pt")
    assert steps == max(load_checkpoint(p)["env_steps"] for p in out.glob("checkpoint_*.pt"))
    assert steps >= 160 and saved["curriculum"]["index"] == 1
    counts = [e["terms"]["counter"]["count"] for e in saved["env"]["ranks"][0]["envs"]]
    adam_steps = saved["optimizer_state_dict"]["state"][0]["step"]

    cfg = tiny_run.config(out, steps + 2 * PER_ITERATION, "behavior.stage_steps=96")
    result = train(
        cfg, tiny_run.registry(), resume=out, infant_factory=tiny_run.factory, progress=False
    )
    assert result.env_steps == steps + 64
    new = [r for r in rows(out) if r["step"] > steps]
    assert [r["step"] for r in new] == [steps + 32, steps + 64]
    assert [r["iteration"] for r in new] == [steps // 32, steps // 32 + 1]  # no repeated index
    assert all(r["stage"] == "random" for r in new)
    final = load_checkpoint(out / "checkpoint_latest.pt")
    assert [e["terms"]["counter"]["count"] for e in final["env"]["ranks"][0]["envs"]] == [
        c + 16 for c in counts
    ]
    # 2 iterations x 2 epochs x 2 mini-batches more Adam steps on the restored optimiser
    assert final["optimizer_state_dict"]["state"][0]["step"] == adam_steps + 8


def test_resume_errors(tmp_path):
    with pytest.raises(UsageError, match="does not exist"):
        train(None, tiny_run.registry(), resume=tmp_path / "missing")
    (tmp_path / "empty").mkdir()
    with pytest.raises(UsageError, match="no checkpoint in .*nothing to resume"):
        train(None, tiny_run.registry(), resume=tmp_path / "empty")
    result = run(tmp_path / "r", 32)
    cfg = tiny_run.config(tmp_path / "r", 64, num_envs=2)
    with pytest.raises(UsageError, match="resume with --envs 4"):
        train(cfg, tiny_run.registry(), resume=result.run_dir, infant_factory=tiny_run.factory)


def test_corrupt_checkpoints_are_refused(tmp_path):
    result = run(tmp_path / "r", 64)
    latest = result.run_dir / "checkpoint_latest.pt"
    data = latest.read_bytes()
    truncated = tmp_path / "truncated.pt"
    truncated.write_bytes(data[: len(data) // 2])
    with pytest.raises(UsageError, match=r"checkpoint .*truncated.pt is corrupt or unreadable"):
        load_checkpoint(truncated)
    foreign = tmp_path / "foreign.pt"
    torch.save({"weights": torch.zeros(2)}, foreign)
    with pytest.raises(UsageError, match="is not a devlearn checkpoint"):
        load_checkpoint(foreign)
    with pytest.raises(UsageError, match="does not exist"):
        load_checkpoint(tmp_path / "nope.pt")
    # a damaged latest falls back to the newest periodic checkpoint that loads
    latest.unlink()  # break the hard link before damaging
    latest.write_bytes(data[:100])
    path, state = resume_checkpoint(result.run_dir)
    assert path.name == "checkpoint_64.pt" and state["env_steps"] == 64


KILL_MID_WRITE = """
import os, signal, sys
from devlearn.training.checkpoint import save_atomic

class KillWhilePickling:
    def __reduce__(self):
        os.kill(os.getpid(), signal.SIGKILL)

save_atomic({"format": "x", "payload": bytes(10_000_000), "bomb": KillWhilePickling()},
            __import__("pathlib").Path(sys.argv[1]))
"""


def test_kill_mid_write_keeps_previous_checkpoint(tmp_path):
    path = tmp_path / "checkpoint_latest.pt"
    save_atomic({"format": "devlearn-checkpoint-1", "behavior": "tiny", "n": 1}, path)
    before = path.read_bytes()
    done = subprocess.run([sys.executable, "-c", KILL_MID_WRITE, str(path)], timeout=60)
    assert done.returncode == -signal.SIGKILL
    assert path.read_bytes() == before
    assert load_checkpoint(path, required=())["n"] == 1
    assert list(tmp_path.glob(".checkpoint_latest.pt.tmp-*"))  # the partial file, not latest


def test_resume_forgets_metrics_logged_after_the_checkpoint(tmp_path):
    from devlearn.training.run_folder import forget_metrics_after

    path = tmp_path / "metrics.jsonl"
    rows = [json.dumps({"step": s}) for s in (100, 200, 300)]
    path.write_text("\n".join(rows) + '\n{"step": 4')  # last line cut short by a kill
    forget_metrics_after(path, 200)
    assert [json.loads(line)["step"] for line in path.read_text().splitlines()] == [100, 200]
    forget_metrics_after(tmp_path / "none.jsonl", 1)  # no file yet: nothing to do


def test_resume_with_a_fixed_schedule_uses_the_configured_learning_rate(tmp_path):
    out = tmp_path / "run"
    run(out, 64, "ppo.learning_rate=0.002")  # adaptive: the rate moves with the KL
    adapted = load_checkpoint(out / "checkpoint_latest.pt")["learning_rate"]
    assert adapted != 0.002  # else this test would not tell the two apart
    fixed = tiny_run.config(out, 96, "ppo.schedule=fixed", "ppo.learning_rate=0.0005")
    train(fixed, tiny_run.registry(), resume=out, infant_factory=tiny_run.factory, progress=False)
    final = load_checkpoint(out / "checkpoint_latest.pt")
    assert final["learning_rate"] == 0.0005
    assert final["optimizer_state_dict"]["param_groups"][0]["lr"] == 0.0005
