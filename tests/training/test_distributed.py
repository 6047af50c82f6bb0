"""Two CPU ranks under torchrun (gloo): parameters stay in sync through PPO updates, every rank
seeds its own environments, steps are counted globally and only rank 0 writes the run files."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from devlearn.training.checkpoint import load_checkpoint

HERE = Path(__file__).resolve().parent


@pytest.fixture(scope="module")
def two_rank_run(tmp_path_factory):
    """Train the tiny behaviour for 128 steps on 2 ranks x 4 envs x 8 steps (2 PPO updates)."""
    out = tmp_path_factory.mktemp("distributed") / "run"
    cmd = [
        sys.executable,
        "-m",
        "torch.distributed.run",
        "--standalone",  # a free rendezvous port on this machine: parallel CI jobs do not clash
        "--nproc_per_node",
        "2",
        str(HERE / "distributed_run.py"),
        str(out),
        "128",
    ]
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=120, env=env)
    assert done.returncode == 0, done.stderr[-3000:]
    return out


@pytest.mark.slow
def test_ranks_hold_identical_parameters_after_updates(two_rank_run):
    ranks = [json.loads((two_rank_run / f"rank{r}.json").read_text()) for r in (0, 1)]
    assert [r["world_size"] for r in ranks] == [2, 2]
    assert [r["iterations"] for r in ranks] == [2, 2]
    # Rank 0's initial parameters are broadcast, then gradients are averaged over gloo.
    assert ranks[0]["before"] == ranks[1]["before"]
    assert ranks[0]["after"] == ranks[1]["after"]
    assert ranks[0]["after"] != ranks[0]["before"]  # the updates did change the networks


@pytest.mark.slow
def test_each_rank_seeds_its_environments_and_noise_differently(two_rank_run):
    rngs = [json.loads((two_rank_run / f"rank{r}.json").read_text())["env_rng"] for r in (0, 1)]
    flat = rngs[0] + rngs[1]
    assert len(set(flat)) == len(flat) == 8  # env i of rank r is seeded seed + r * 4 + i
    torch_rngs = [
        json.loads((two_rank_run / f"rank{r}.json").read_text())["torch_rng"] for r in (0, 1)
    ]
    assert torch_rngs[0] != torch_rngs[1]  # each rank samples its own action noise


@pytest.mark.slow
def test_steps_counted_globally_and_rank0_writes_the_run(two_rank_run):
    rows = (two_rank_run / "metrics.jsonl").read_text().splitlines()
    assert [json.loads(line)["step"] for line in rows] == [64, 128]  # logged once, by rank 0
    state = load_checkpoint(two_rank_run / "checkpoint_latest.pt")
    assert state["env_steps"] == 128 and len(state["env"]["ranks"]) == 2
    for rank in state["env"]["ranks"]:
        assert [e["terms"]["counter"]["count"] for e in rank["envs"]] == [16] * 4


@pytest.mark.slow
def test_run_wide_reward_memory_is_merged_across_ranks(tmp_path):
    """Each rank's term memory differs (rank 1 alone would hold 14, rank 0 4); at every
    iteration boundary the ranks' memories are merged (maximum), so all envs of both ranks
    hold 14 in the checkpoint."""
    out = tmp_path / "run"
    cmd = [sys.executable, "-m", "torch.distributed.run", "--standalone", "--nproc_per_node", "2"]
    cmd += [str(HERE / "distributed_memory_run.py"), str(out), "64"]
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=120, env=env)
    assert done.returncode == 0, done.stderr[-3000:]
    state = load_checkpoint(out / "checkpoint_latest.pt")
    widest = [e["terms"]["step_novelty"]["widest"].tolist() for r in state["env"]["ranks"]
              for e in r["envs"]]
    assert widest == [[14]] * 8
