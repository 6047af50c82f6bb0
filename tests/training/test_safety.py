"""Safe runs: data-only checkpoints, guards on rewards and observations, faults, start-up."""

from __future__ import annotations

import functools
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import tiny_run
import torch

import devlearn
from devlearn.api.errors import RunStopped, UsageError
from devlearn.env.guards import GuardError
from devlearn.testing import registry_for, run_config
from devlearn.testing.fake_infant import TinyBehavior, TinyConfig, fake_infant_factory
from devlearn.training import train
from devlearn.training.checkpoint import (
    FORMAT,
    RESUME_KEYS,
    allowed_globals,
    load_checkpoint,
    resume_checkpoint,
)

ROOT = Path(__file__).resolve().parents[2]
PER_ITERATION = 32  # 4 envs x 8 steps


class Payload:
    """Unpickling this runs ``exec``, which writes a marker file."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return exec, (f"open({str(self.marker)!r}, 'w').write('ran')",)


def test_published_checkpoints_load_as_data():
    published = sorted(ROOT.glob("results/**/*.pt"))
    assert published, "no published checkpoints found under results/"
    for path in published:
        state = load_checkpoint(path)
        assert state["behavior"] and state["actor_state_dict"]


def test_new_checkpoints_load_with_weights_only(tmp_path):
    result = train(
        tiny_run.config(tmp_path / "r", 32),
        tiny_run.registry(),
        infant_factory=tiny_run.factory,
        progress=False,
    )
    with torch.serialization.safe_globals(allowed_globals()):
        state = torch.load(result.run_dir / "checkpoint_latest.pt", weights_only=True)
    assert state["format"] == FORMAT and all(k in state for k in RESUME_KEYS)


def test_a_payload_is_refused_unrun(tmp_path):
    marker = tmp_path / "marker"
    path = tmp_path / "crafted.pt"
    torch.save({"format": FORMAT, "behavior": "tiny", "x": Payload(marker)}, path)
    with pytest.raises(UsageError, match=r"refused: it needs builtins\.exec.*nothing in it"):
        load_checkpoint(path)
    assert not marker.exists()


def test_link_fallback_copies_bytes_and_unpickles_nothing(tmp_path, monkeypatch):
    import os

    from devlearn.training.checkpoint import link_atomic

    marker = tmp_path / "marker"
    source = tmp_path / "checkpoint_32.pt"
    torch.save({"format": FORMAT, "x": Payload(marker)}, source)

    def no_links(*args):
        raise OSError(1, "hard links unsupported")

    monkeypatch.setattr(os, "link", no_links)
    link_atomic(source, tmp_path / "checkpoint_latest.pt")
    assert (tmp_path / "checkpoint_latest.pt").read_bytes() == source.read_bytes()
    assert not marker.exists() and not list(tmp_path.glob(".*tmp-*"))


def _run(out: Path, steps: int, **kwargs):
    cfg = tiny_run.config(out, steps)
    registry = tiny_run.registry()
    return train(cfg, registry, infant_factory=tiny_run.factory, progress=False, **kwargs)


def test_resume_picks_the_newest_checkpoint_and_removes_temporaries(tmp_path):
    out = _run(tmp_path / "r", 96).run_dir
    (out / "checkpoint_latest.pt").unlink()
    (out / "checkpoint_latest.pt").write_bytes((out / "checkpoint_32.pt").read_bytes())
    path, state = resume_checkpoint(out)
    assert path.name == "checkpoint_96.pt" and state["env_steps"] == 96
    stale = out / ".checkpoint_latest.pt.tmp-4242"
    stale.write_bytes(b"partial")
    cfg = tiny_run.config(out, 128)
    train(cfg, tiny_run.registry(), resume=out, infant_factory=tiny_run.factory, progress=False)
    assert not stale.exists()
    assert [json.loads(r)["step"] for r in (out / "metrics.jsonl").read_text().splitlines()] == [
        32,
        64,
        96,
        128,
    ]


# --- guards ---------------------------------------------------------------------------------


@dataclass
class BadConfig(TinyConfig):
    """TinyConfig plus a term that goes bad."""

    bad_value: float = math.nan
    """What the ``explode`` term returns once it goes bad."""
    bad_from: int = 20
    """Lifetime step of each env from which it goes bad (at episode step 3)."""
    bad_observation: bool = False
    """Spoil the proprioception observation instead of the reward."""
    bad_raise: bool = False
    """The ``explode`` term raises ZeroDivisionError instead of returning ``bad_value``."""


class Explode(devlearn.IntrinsicReward):
    """Pays 0, then ``bad_value`` at episode step 3 from lifetime step ``bad_from`` on."""

    name = "explode"

    def __init__(self, value: float, start: int, raises: bool = False) -> None:
        super().__init__(1.0)
        self.value, self.start, self.count, self.raises = value, start, 0, raises

    def __call__(self, ctx) -> float:
        self.count += 1
        bad = self.count > self.start and ctx.step == 3
        if bad and self.raises:
            return 1 / 0
        return self.value if bad else 0.0


class BadTiny(TinyBehavior):
    """The tiny behaviour with a reward term (or observation) that turns non-finite."""

    name = "bad"
    config_class = BadConfig

    def reward_terms(self):
        return [
            *super().reward_terms(),
            Explode(self.config.bad_value, self.config.bad_from, self.config.bad_raise),
        ]

    def observe(self, batch, facts):
        obs = {name: np.array(rows) for name, rows in super().observe(batch, facts).items()}
        for i, infant in enumerate(batch.infants):
            if self.config.bad_observation and infant.steps_taken > self.config.bad_from:
                obs["proprioception"][i] = np.inf
        return obs


def bad_config(out: Path, *overrides: str, **top):
    """The bad behaviour's config: 4 envs x 8 steps per iteration, in process by default."""
    top = {"num_envs": 4, "workers": 0, "save_interval": 1, **top}
    return run_config(
        BadTiny, list(overrides), out_dir=str(out), total_steps=100_000, **top
    )


@pytest.mark.parametrize(("value", "workers"), [("nan", 0), ("inf", 0), ("1e30", 0), ("-inf", 1)])
def test_a_bad_reward_stops_training_named_with_a_good_checkpoint(tmp_path, value, workers):
    out = tmp_path / "r"
    cfg = bad_config(out, f"behavior.bad_value={value}", workers=workers)
    with pytest.raises(RunStopped) as caught:
        train(cfg, registry_for(BadTiny), infant_factory=tiny_run.factory, progress=False)
    message = str(caught.value)
    assert f"reward term 'explode' returned {float(value)!r} in env 0 at episode step 3" in message
    assert "\n" not in message and "step 64" in message and f"--resume {out}" in message
    # 16 steps per env are done after 2 iterations; the 3rd iteration (steps 17-24) goes bad
    # at lifetime step 24 (episode step 3): the checkpoint holds the end of iteration 2
    state = load_checkpoint(out / "checkpoint_latest.pt", RESUME_KEYS)
    assert state["env_steps"] == 2 * PER_ITERATION and state["iteration"] == 2
    assert [e["terms"]["counter"]["count"] for e in state["env"]["ranks"][0]["envs"]] == [16] * 4
    rows = [json.loads(r) for r in (out / "metrics.jsonl").read_text().splitlines()]
    assert [r["step"] for r in rows] == [32, 64]
    assert all(math.isfinite(v) for r in rows for v in r.values() if isinstance(v, float))


@pytest.mark.parametrize("workers", [0, 2])
def test_a_term_that_raises_stops_training_named_with_a_good_checkpoint(tmp_path, workers):
    out = tmp_path / "r"
    cfg = bad_config(out, "behavior.bad_raise=true", workers=workers)
    with pytest.raises(RunStopped) as caught:
        train(cfg, registry_for(BadTiny), infant_factory=tiny_run.factory, progress=False)
    message = str(caught.value)
    assert (
        "reward term 'explode' raised ZeroDivisionError: division by zero in env 0 at episode "
        "step 3" in message
    )
    assert "\n" not in message and "step 64" in message and f"--resume {out}" in message
    state = load_checkpoint(out / "checkpoint_latest.pt", RESUME_KEYS)
    assert state["env_steps"] == 2 * PER_ITERATION


def test_a_bad_observation_stops_training_named(tmp_path):
    out = tmp_path / "r"
    cfg = bad_config(out, "behavior.bad_observation=true", "behavior.bad_value=0")
    with pytest.raises(RunStopped, match="observation 'proprioception' holds inf in env 0"):
        train(cfg, registry_for(BadTiny), infant_factory=tiny_run.factory, progress=False)
    assert load_checkpoint(out / "checkpoint_latest.pt")["env_steps"] == 2 * PER_ITERATION


def test_a_guard_error_survives_pickling():
    """A GuardError travels back from a worker process with its message."""
    error = GuardError("reward term", "x", 1e30, 1, 2)
    import pickle

    assert str(pickle.loads(pickle.dumps(error))) == str(error)


# --- faults and interrupts ------------------------------------------------------------------


def test_a_killed_worker_leaves_a_resumable_checkpoint(tmp_path):
    out = tmp_path / "r"
    dying = functools.partial(fake_infant_factory, episode_steps=10, die_after=20)
    cfg = tiny_run.config(out, 100_000, workers=1)
    with pytest.raises(
        RunStopped,
        match=r"env worker \d \(pid \d+\) died unexpectedly, killed by "
        r"SIGKILL.*last good state \(step 64\)",
    ) as caught:
        train(cfg, tiny_run.registry(), infant_factory=dying, progress=False)
    # two iterations completed (rows 0 and 1 of metrics.jsonl), the third was under way
    assert "during iteration 3 of 3125;" in str(caught.value)
    _, state = resume_checkpoint(out)
    assert state["env_steps"] == 2 * PER_ITERATION
    cfg = tiny_run.config(out, 3 * PER_ITERATION)
    result = train(
        cfg, tiny_run.registry(), resume=out, infant_factory=tiny_run.factory, progress=False
    )
    assert result.env_steps == 3 * PER_ITERATION


# --- start-up: the run folder ---------------------------------------------------------------


def files(run_dir: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(run_dir)): p.read_bytes()
        for p in sorted(run_dir.rglob("*"))
        if p.is_file()
    }


def test_a_new_run_on_an_existing_run_is_refused_and_force_replaces_it(tmp_path):
    out = _run(tmp_path / "r", 64).run_dir
    before = files(out)
    with pytest.raises(UsageError, match="already holds a run; continue it with --resume .*force"):
        _run(out, 64)
    assert files(out) == before
    _run(out, 32, force=True)
    assert [json.loads(r)["step"] for r in (out / "metrics.jsonl").read_text().splitlines()] == [32]
    assert not (out / "checkpoint_64.pt").exists()


def test_a_failed_start_leaves_the_folder_as_it_was(tmp_path, monkeypatch):
    import importlib

    train_module = importlib.import_module("devlearn.training.train")  # not the function
    out = _run(tmp_path / "r", 64).run_dir
    before = files(out)

    def broken(*args, **kwargs):
        raise RuntimeError("envs cannot be built")

    monkeypatch.setattr(train_module, "DevVecEnv", broken)
    for kwargs in ({"resume": out}, {"force": True}):
        cfg = tiny_run.config(out, 128, "behavior.target=0.25")
        with pytest.raises(RuntimeError, match="envs cannot be built"):
            train(cfg, tiny_run.registry(), infant_factory=tiny_run.factory, **kwargs)
        assert files(out) == before
    fresh = tmp_path / "new" / "run"
    with pytest.raises(RuntimeError, match="envs cannot be built"):
        train(tiny_run.config(fresh, 32), tiny_run.registry(), infant_factory=tiny_run.factory)
    assert not (tmp_path / "new").exists()


def test_tensorboard_hides_iterations_a_resume_redoes(tmp_path):
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    out = _run(tmp_path / "r", 96).run_dir  # iterations 0, 1, 2 logged
    (out / "checkpoint_96.pt").unlink()  # as if killed between logging iteration 2 and saving it
    (out / "checkpoint_latest.pt").unlink()
    (out / "checkpoint_latest.pt").write_bytes((out / "checkpoint_64.pt").read_bytes())
    cfg = tiny_run.config(out, 128)
    train(cfg, tiny_run.registry(), resume=out, infant_factory=tiny_run.factory, progress=False)
    events = EventAccumulator(str(out), purge_orphaned_data=True)
    events.Reload()
    steps = [e.step for e in events.Scalars("Loss/learning_rate")]
    assert steps == [0, 1, 2, 3]


def test_an_interrupt_while_an_iteration_closes_saves_what_metrics_record(tmp_path, monkeypatch):
    """Ctrl-C landing after the boundary snapshot but before its metrics row is written (the
    race a scheduler's SIGTERM can hit) is held until the row is written, so the checkpoint and
    metrics.jsonl agree."""
    import os
    import signal

    from devlearn.training.runner_metrics import MetricsLog

    real = MetricsLog.record
    calls = []

    def interrupted_record(self, *args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            os.kill(os.getpid(), signal.SIGINT)
        return real(self, *args, **kwargs)

    monkeypatch.setattr(MetricsLog, "record", interrupted_record)
    out = tmp_path / "r"
    # Ctrl-C as `devlearn run` sets it up, whatever this process inherited (a shell's `cmd &`
    # starts pytest with SIGINT ignored, and the kill below would then do nothing).
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            _run(out, 32 * 10)
    finally:
        signal.signal(signal.SIGINT, previous)
    saved = load_checkpoint(out / "checkpoint_latest.pt")["env_steps"]
    rows = [json.loads(line) for line in (out / "metrics.jsonl").read_text().splitlines()]
    assert saved == rows[-1]["step"] == 64
