"""Learned rewards in training: config, the rollout batch, rewards added, logs, resume."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
import tiny_run
import torch
from tensordict import TensorDict

from devlearn.testing.fake_infant import TinyBehavior

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from learned_terms import LinearPredictor  # noqa: E402

from devlearn.api.errors import UsageError  # noqa: E402
from devlearn.testing import registry_for  # noqa: E402
from devlearn.training import train  # noqa: E402
from devlearn.training.checkpoint import load_checkpoint  # noqa: E402
from devlearn.training.learned_rewards import LearnedRewards, transitions  # noqa: E402

REGISTRY = registry_for(TinyBehavior, learned_rewards=(LinearPredictor,))


def run(out: Path, steps: int, *overrides: str, resume: Path | None = None):
    cfg = tiny_run.config(out, steps, *overrides)
    return train(cfg, REGISTRY, resume=resume, infant_factory=tiny_run.factory, progress=False)


def rows(run_dir: Path) -> list[dict]:
    return [json.loads(line) for line in (run_dir / "metrics.jsonl").read_text().splitlines()]


def test_names_and_options_are_checked_before_anything_runs(tmp_path):
    with pytest.raises(UsageError, match="unknown learned reward 'lineer'; installed: linear"):
        run(tmp_path / "a", 32, "curiosity=lineer")
    with pytest.raises(UsageError, match=r"unknown option 'learned.linear.wieght'; valid opt"):
        run(tmp_path / "b", 32, "curiosity=linear", "learned.linear.wieght=2")
    with pytest.raises(UsageError, match="learned.linear.weight"):
        run(tmp_path / "c", 32, "curiosity=linear", "learned.linear.weight=lots")
    with pytest.raises(UsageError, match="not in curiosity"):
        run(tmp_path / "d", 32, "learned.linear.weight=2")
    assert not (tmp_path / "a").exists()  # failed before the run directory was made


class _Storage:
    """The parts of rsl-rl's RolloutStorage that learned rewards read: T=3 steps, N=2 envs."""

    def __init__(self):
        self.observations = TensorDict(
            {"proprioception": torch.arange(6.0).view(3, 2, 1)}, batch_size=[3, 2]
        )
        self.actions = torch.zeros(3, 2, 1)
        self.rewards = torch.ones(3, 2, 1)
        self.dones = torch.tensor([[0, 0], [1, 0], [0, 0]], dtype=torch.uint8).view(3, 2, 1)


def test_transitions_pair_each_step_with_the_next_and_skip_finished_episodes():
    storage = _Storage()
    last = TensorDict({"proprioception": torch.tensor([[6.0], [7.0]])}, batch_size=[2])
    batch, valid = transitions(storage, last)
    assert valid.tolist() == [True, True, False, True, True, True]  # env 0 ended at step 1
    assert batch.observations["proprioception"].view(-1).tolist() == [0, 1, 3, 4, 5]
    assert batch.next_observations["proprioception"].view(-1).tolist() == [2, 3, 5, 6, 7]


def test_apply_adds_the_weighted_reward_where_episodes_went_on():
    storage = _Storage()
    last = TensorDict({"proprioception": torch.tensor([[6.0], [7.0]])}, batch_size=[2])
    cfg = tiny_run.config(
        "unused",
        32,
        "curiosity=linear",
        "learned.linear.weight=0.5",
        "learned.linear.normalize=false",
    )
    learned = LearnedRewards.from_config(cfg, REGISTRY).build({"proprioception": (1,)}, 1, "cpu")
    term = learned.terms["linear"]
    batch, _ = transitions(storage, last)
    with torch.no_grad():
        raw = term.compute_reward(batch)
    with torch.inference_mode():  # as in the runner's rollout
        row = learned.apply(storage, last, env_steps=0)
    added = storage.rewards.view(-1) - 1.0
    assert added[2] == 0.0  # the finished episode's step gets nothing
    torch.testing.assert_close(added[[0, 1, 3, 4, 5]], 0.5 * raw)
    assert row["reward/linear/weight"] == 0.5
    assert row["reward/linear/raw"] == pytest.approx(float(raw.mean()))
    assert row["reward/linear/step"] == pytest.approx(float(added.mean()))


def test_a_run_logs_the_term_and_saves_it_with_weights_only_types(tmp_path):
    result = run(tmp_path / "r", 64, "curiosity=linear")
    for row in rows(result.run_dir):
        for key in ("step", "raw", "loss", "weight"):
            assert f"reward/linear/{key}" in row
    config = json.loads((result.run_dir / "config.json").read_text())
    assert config["curiosity"] == ["linear"] and config["learned"]["linear"]["weight"] == 0.1
    state = load_checkpoint(result.run_dir / "checkpoint_latest.pt")["learned"]
    assert state["linear"]["updates"] == 2
    path = tmp_path / "learned.pt"
    torch.save(state, path)
    torch.load(path, weights_only=True)  # only tensors, dicts, lists, numbers, strings
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    events = EventAccumulator(str(result.run_dir))
    events.Reload()
    assert "reward/linear/loss" in events.Tags()["scalars"]


def test_resume_restores_and_continues_the_model_and_optimiser(tmp_path):
    out = tmp_path / "r"
    run(out, 64, "curiosity=linear")
    saved = load_checkpoint(out / "checkpoint_latest.pt")["learned"]["linear"]
    # Resume with nothing left to do: the final checkpoint holds exactly what was restored.
    run(out, 64, "curiosity=linear", resume=out)
    again = load_checkpoint(out / "checkpoint_latest.pt")["learned"]["linear"]
    for key, tensor in saved["model"].items():
        torch.testing.assert_close(again["model"][key], tensor, rtol=0, atol=0)
    assert again["optimizer"]["state"][0]["step"] == saved["optimizer"]["state"][0]["step"]
    torch.testing.assert_close(again["scale"]["m2"], saved["scale"]["m2"], rtol=0, atol=0)
    # Two more iterations continue the counters.
    run(out, 128, "curiosity=linear", resume=out)
    later = load_checkpoint(out / "checkpoint_latest.pt")["learned"]["linear"]
    assert later["updates"] == 4
    assert later["optimizer"]["state"][0]["step"] == 2 * saved["optimizer"]["state"][0]["step"]
    assert later["scale"]["count"] > saved["scale"]["count"]


def test_resume_refuses_other_learned_rewards(tmp_path):
    out = tmp_path / "r"
    run(out, 32, "curiosity=linear")
    with pytest.raises(UsageError, match="resume with --set curiosity=linear"):
        run(out, 64, resume=out)


@pytest.mark.slow
def test_torchrun_ranks_share_one_learned_model(tmp_path):
    import os
    import subprocess

    out = tmp_path / "run"
    script = Path(__file__).resolve().parent / "distributed_learned_run.py"
    cmd = [
        sys.executable,
        "-m",
        "torch.distributed.run",
        "--standalone",
        "--nproc_per_node",
        "2",
        str(script),
        str(out),
        "128",
    ]
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=120, env=env)
    assert done.returncode == 0, done.stderr[-3000:]
    ranks = [json.loads((out / f"learned{r}.json").read_text()) for r in (0, 1)]
    assert ranks[0]["before"] == ranks[1]["before"]  # rank 0's initial model, broadcast
    assert ranks[0]["after"] == ranks[1]["after"] != ranks[0]["before"]  # averaged updates
    # Each rank rewarded its own rollout (different environments), with one shared model.
    assert ranks[0]["last"]["reward/linear/raw"] != ranks[1]["last"]["reward/linear/raw"]
    assert load_checkpoint(out / "checkpoint_latest.pt")["learned"]["linear"]["updates"] == 2


def test_a_non_finite_learned_reward_stops_the_run_at_the_last_good_state(tmp_path, monkeypatch):
    from devlearn.api.errors import RunStopped

    def broken(self, batch):
        errors = self.errors(batch)
        if self.updates == 1:  # the second iteration goes wrong
            errors[3] = float("nan")
        return errors

    monkeypatch.setattr(LinearPredictor, "compute_reward", broken)
    with pytest.raises(RunStopped, match="learned reward 'linear' gave nan for env"):
        run(tmp_path / "r", 128, "curiosity=linear")
    state = load_checkpoint(tmp_path / "r" / "checkpoint_latest.pt")
    assert state["env_steps"] == 32 and state["learned"]["linear"]["updates"] == 1
