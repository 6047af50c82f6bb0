"""Two CPU ranks under torchrun (gloo): global step count, rank-0 files, every rank's env state."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import tiny_run

from devlearn.training.checkpoint import load_checkpoint


@pytest.mark.slow
def test_two_cpu_ranks(tmp_path):
    out = tmp_path / "run"
    cmd = [
        sys.executable,
        "-m",
        "torch.distributed.run",
        "--nproc_per_node",
        "2",
        "--master_port",
        "29531",
        str(Path(tiny_run.__file__)),
        str(out),
        "128",
    ]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=240)
    assert done.returncode == 0, done.stderr[-3000:]
    steps = [json.loads(line)["step"] for line in (out / "metrics.jsonl").read_text().splitlines()]
    assert steps == [64, 128]  # 2 ranks x 4 envs x 8 steps per iteration, logged once
    state = load_checkpoint(out / "checkpoint_latest.pt")
    assert state["env_steps"] == 128 and len(state["env"]["ranks"]) == 2
    for rank in state["env"]["ranks"]:
        assert [e["terms"]["counter"]["count"] for e in rank["envs"]] == [16] * 4
    # rank 1's envs are seeded differently from rank 0's
    assert state["env"]["ranks"][0]["envs"][0]["rng"] != state["env"]["ranks"][1]["envs"][0]["rng"]
