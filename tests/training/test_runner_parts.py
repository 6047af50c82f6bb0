"""The runner's parts, each built alone: RunCheckpoints (snapshot, save, restore) and MetricsLog
(metrics.jsonl rows, run metrics fed every episode record)."""

from __future__ import annotations

import json
import random

import numpy as np
import tiny_run
import torch

from devlearn.api.curriculum import Curriculum, Stage
from devlearn.env.behavior_env import EPISODE_RECORD
from devlearn.training.checkpoint import RESUME_KEYS, load_checkpoint
from devlearn.training.learned_rewards import LearnedRewards
from devlearn.training.process import Ranks
from devlearn.training.runner_checkpoints import RunCheckpoints
from devlearn.training.runner_metrics import IterationFigures, MetricsLog


class FakeAlg:
    """What RunCheckpoints uses of PPO: save, load, learning_rate, optimizer."""

    def __init__(self) -> None:
        self.weights = torch.arange(4.0)
        self.learning_rate = 1e-3
        self.optimizer = torch.optim.SGD([torch.nn.Parameter(torch.zeros(1))], lr=1e-3)

    def save(self) -> dict:
        return {
            "actor_state_dict": {"w": self.weights},
            "critic_state_dict": {"w": self.weights * 2},
            "optimizer_state_dict": self.optimizer.state_dict(),
        }

    def load(self, state: dict, _: object, strict: bool) -> None:
        self.weights = state["actor_state_dict"]["w"].clone()


class FakeEnv:
    """What RunCheckpoints uses of DevVecEnv: state_dict, load_state_dict, sync_run_memory,
    the body's age."""

    def __init__(self) -> None:
        self.state = {"envs": [{"count": 1}, {"count": 2}]}
        self.synced = 0
        self.age_months: float | None = None

    def state_dict(self) -> dict:
        return self.state

    def load_state_dict(self, state: dict) -> None:
        self.state = state

    def sync_run_memory(self, gather: object) -> None:
        self.synced += 1


def curriculum() -> Curriculum:
    return Curriculum([Stage("fixed", 64, {"random_pose": False}), Stage("random", 0, {})])


def checkpoints(tmp_path, alg=None, env=None) -> RunCheckpoints:
    cfg = tiny_run.config(tmp_path, 128)
    return RunCheckpoints(
        alg or FakeAlg(),
        env or FakeEnv(),
        curriculum(),
        LearnedRewards(),
        None,
        None,
        cfg,
        tmp_path,
        Ranks(),
    )


def test_checkpoints_save_a_snapshot_and_restore_it(tmp_path):
    parts = checkpoints(tmp_path)
    parts.curriculum.update(96)  # the random stage
    parts.env.age_months = 7.5  # a growing body's age at the boundary
    torch.manual_seed(5)
    good = parts.snapshot(iteration=3, env_steps=96)
    expected = torch.rand(3)  # what the restored generator draws next
    parts.alg.weights = torch.zeros(4)  # the state moves on after the snapshot...
    parts.env.state = {"envs": []}
    assert parts.save(good, periodic=True) == tmp_path / "checkpoint_latest.pt"
    # ...but the files hold the boundary, in the format every reader checks
    assert sorted(p.name for p in tmp_path.glob("checkpoint_*.pt")) == [
        "checkpoint_96.pt",
        "checkpoint_latest.pt",
    ]
    state = load_checkpoint(tmp_path / "checkpoint_96.pt", RESUME_KEYS)
    assert (state["iteration"], state["env_steps"], state["behavior"]) == (3, 96, "tiny")
    assert state["env"] == {"ranks": [{"envs": [{"count": 1}, {"count": 2}]}]}
    assert state["config"]["total_steps"] == 128
    assert state["age_months"] == 7.5

    fresh = checkpoints(tmp_path, env=FakeEnv())
    fresh.env.state = {"envs": []}
    random.seed(0), np.random.seed(0), torch.manual_seed(0)
    assert fresh.restore(state) == (3, 96)
    assert torch.equal(fresh.alg.weights, torch.arange(4.0))
    assert fresh.env.state == {"envs": [{"count": 1}, {"count": 2}]} and fresh.env.synced == 1
    assert fresh.curriculum.stage.name == "random"
    assert fresh.env.age_months is None  # the body is the run's config's (train() built it)
    assert torch.equal(torch.rand(3), expected)


def test_a_branch_keeps_its_own_curriculum_and_a_fault_saves_the_last_boundary(tmp_path):
    parts = checkpoints(tmp_path)
    state = parts.checkpoint_state(parts.snapshot(1, 32))
    state["curriculum"] = {"index": 1}  # the source had switched...
    branch = checkpoints(tmp_path / "b")
    branch.restore(state, curriculum=False)  # ...the branch's stage follows its steps
    assert branch.curriculum.stage.name == "fixed"
    message = parts.save_after_fault(None)
    assert "no checkpoint could be written" in message
    message = parts.save_after_fault(parts.snapshot(2, 64))
    assert "step 64" in message and f"--resume {tmp_path}" in message
    assert load_checkpoint(tmp_path / "checkpoint_latest.pt")["env_steps"] == 64


class CountingMetrics:
    """A RunMetrics that counts the records it was given."""

    def __init__(self) -> None:
        self.records: list = []

    def add(self, records: list) -> None:
        self.records += records

    def values(self) -> dict:
        return {"seen": len(self.records)}


class Bar:
    """What MetricsLog uses of a tqdm bar."""

    total, n = 64, 0

    def set_postfix(self, postfix: dict, refresh: bool) -> None:
        self.postfix = postfix

    def update(self, steps: int) -> None:
        self.n += steps


def test_metrics_log_writes_one_row_per_iteration_over_the_last_episodes(tmp_path):
    run_metrics = CountingMetrics()
    log = MetricsLog(tmp_path, curriculum(), LearnedRewards(), run_metrics, "seen")
    finished = [
        {"reward/a": 1.0, "reward/b": 2.0, EPISODE_RECORD: "x"},
        {"reward/a": 3.0, "reward/b": 0.0, EPISODE_RECORD: "y"},
    ]
    log.add_episode_records(finished, all_ranks=lambda records: [records, ["z"]])
    assert run_metrics.records == ["x", "y", "z"]  # every rank's, in rank order
    assert all(EPISODE_RECORD not in ep for ep in finished)  # only numbers are averaged
    bar = Bar()
    times = {"collect_s": 1.0, "update_s": 0.5, "update_threads": 1}
    first = IterationFigures(
        iteration=0,
        env_steps=32,
        finished=finished,
        mean_step_reward=0.25,
        losses={"value": 2.0},
        steps_per_s=21.3,
        times=times,
    )
    row = log.record(first, bar, None)
    assert row["step"] == 32 and row["iteration"] == 0 and row["stage"] == "fixed"
    assert row["mean_reward"] == 3.0  # (1 + 2 + 3 + 0) / 2 episodes
    assert (row["reward/a"], row["loss/value"], row["metrics/seen"]) == (2.0, 2.0, 3)
    log.record(IterationFigures(1, 64, [], 0.5, {"value": 1.0}, 20.0, times), bar, None)
    lines = [json.loads(x) for x in (tmp_path / "metrics.jsonl").read_text().splitlines()]
    assert [r["step"] for r in lines] == [32, 64]
    assert lines[1]["episodes"] == 0 and lines[1]["mean_reward"] == 3.0  # the last episodes
    assert log.last_row == lines[1] and bar.n == 64 and bar.postfix["seen"] == "3"
    quiet = MetricsLog(tmp_path / "other", curriculum(), LearnedRewards(), None, is_main=False)
    quiet.record(IterationFigures(0, 32, [], 0.0, {}, 1.0, times), Bar(), None)
    assert not (tmp_path / "other").exists()  # only rank 0 writes
