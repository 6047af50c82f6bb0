"""A tiny training run, fresh, resumed and branched, reproduces numbers recorded before the
runner and config refactor (issue #31) bit for bit.

The numbers in ``data/recorded_tiny_run.json`` were written by this file run as a script
(``python tests/training/test_recorded_run.py``) at the code before the refactor; re-record
them only for a change that is meant to change what training computes.
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path

import pytest
import tiny_run
import torch

from devlearn.training import train
from devlearn.training.checkpoint import load_checkpoint

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from cpu_kind import for_this_cpu, to_record  # noqa: E402

RECORDED = Path(__file__).parent / "data" / "recorded_tiny_run.json"
"""The reference recording; ``for_this_cpu(RECORDED)`` the one of this kind of CPU
(``tests/cpu_kind.py``; the Intel AVX-512 one was made with the code of 913aa79)."""
TIMINGS = {"steps_per_s", "collect_s", "update_s", "update_threads"}
"""metrics.jsonl columns that measure wall-clock time (or depend on it)."""
ALIASES = {"metrics/episode_close_mean"}
"""Columns added after the recording that repeat a recorded one under another name (issue #55:
the headline as evaluation names it, ``metrics/close`` here; test_run_summary checks it)."""


def weights_hash(state: dict[str, torch.Tensor]) -> str:
    """sha256 over a state dict's tensors' bytes, in key order."""
    digest = hashlib.sha256()
    for key in sorted(state):
        digest.update(key.encode())
        digest.update(state[key].detach().cpu().contiguous().numpy().tobytes())
    return digest.hexdigest()


def summary(run_dir: Path) -> dict:
    """The run's metrics rows (timings dropped) and its latest checkpoint's weight hashes."""
    rows = [json.loads(line) for line in (run_dir / "metrics.jsonl").read_text().splitlines()]
    state = load_checkpoint(run_dir / "checkpoint_latest.pt")
    return {
        "rows": [{k: v for k, v in r.items() if k not in TIMINGS | ALIASES} for r in rows],
        "actor": weights_hash(state["actor_state_dict"]),
        "critic": weights_hash(state["critic_state_dict"]),
        "env_steps": state["env_steps"],
    }


def _config(out: Path, steps: int):
    # issue #28's learner, which the recording was made with (issue #54 changed the defaults)
    old_learner = ["network.encoders=behavior", "network.activation=relu", "network.init=torch",
                   "network.head=gaussian", "network.final_std=0", "ppo.adam_eps=1e-8",
                   "ppo.normalize_advantage_per_mini_batch=false",
                   "network.exploration_beta=0"]  # fmt: skip
    return tiny_run.config(out, steps, "torch_threads=1", *old_learner, seed=3, save_interval=2)


def _train(cfg, **kwargs):
    return train(cfg, tiny_run.registry(), infant_factory=tiny_run.factory, progress=False, **kwargs)


def record_runs(root: Path) -> dict:
    """Train the three runs under ``root``; return their summaries.

    fresh: 128 steps (4 iterations of 4 envs x 8 steps); resumed: 64 steps, then resumed to
    128; branched: a new run from the first run's step-64 checkpoint (``--from``) to 128.
    """
    fresh = _train(_config(root / "fresh", 128)).run_dir
    half = _train(_config(root / "resumed", 64)).run_dir
    _train(_config(root / "resumed", 128), resume=half)
    source = fresh / "checkpoint_64.pt"
    cfg = _config(root / "branched", 128)
    _train(cfg, start_from=source)
    return {name: summary(root / name) for name in ("fresh", "resumed", "branched")}


@pytest.mark.slow  # about 15 s: three tiny trainings
def test_tiny_runs_repeat_the_recorded_numbers(tmp_path):
    recorded = json.loads(for_this_cpu(RECORDED).read_text())
    got = record_runs(tmp_path)
    for name in ("fresh", "resumed", "branched"):
        assert got[name]["rows"] == recorded[name]["rows"], name
        assert got[name]["actor"] == recorded[name]["actor"], name
        assert got[name]["critic"] == recorded[name]["critic"], name
        assert got[name]["env_steps"] == recorded[name]["env_steps"], name


if __name__ == "__main__":
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        target = to_record(RECORDED)
        target.write_text(json.dumps(record_runs(Path(tmp)), indent=1) + "\n")
    print(f"recorded {target}", file=sys.stderr)
