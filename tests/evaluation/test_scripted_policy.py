"""Scripted policy files (another learner's, through devlearn.gym.save_policy): devlearn eval runs
them under the same protocol as its checkpoints and baselines."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

import devlearn.gym
from devlearn.api.errors import UsageError
from devlearn.evaluation.evaluate import EvalRequest, Evaluation
from devlearn.evaluation.scripted_policy import ScriptedPolicy
from devlearn.gym.env import DevlearnEnv
from devlearn.testing import registry_for
from devlearn.testing.fake_infant import TinyBehavior, fake_infant_factory
from devlearn.training.checkpoint import is_scripted_policy, load_checkpoint

REGISTRY = registry_for(TinyBehavior)


class Still(torch.nn.Module):
    """The zero action whatever it sees."""

    def forward(self, proprioception: torch.Tensor) -> torch.Tensor:
        return torch.zeros_like(proprioception)


class Reach(torch.nn.Module):
    """Moves every joint toward 0.5: the action 5 * (0.5 - position), clipped."""

    def forward(self, proprioception: torch.Tensor) -> torch.Tensor:
        return torch.clamp(5.0 * (0.5 - proprioception), -1.0, 1.0)


@pytest.fixture()
def env():
    env = DevlearnEnv(
        "tiny",
        {"seed": 4, "env.action_repeat": 2},
        registry=REGISTRY,
        infant_factory=fake_infant_factory,
    )
    yield env
    env.close()


def run(path, **kwargs) -> dict:
    request = EvalRequest("tiny", path, episodes=2, **kwargs)
    return Evaluation(request, REGISTRY, infant_factory=fake_infant_factory, progress=False).run()


def test_a_zero_scripted_policy_scores_exactly_the_zero_baseline(env, tmp_path):
    path = devlearn.gym.save_policy(Still(), env, tmp_path / "policy.pt", learner="mine")
    assert is_scripted_policy(path) and not is_scripted_policy(tmp_path / "nothing.pt")
    ours = run(path)
    zero = Evaluation(
        EvalRequest("tiny", episodes=2, policy="zero", overrides=["env.action_repeat=2"]),
        REGISTRY,
        infant_factory=fake_infant_factory,
        progress=False,
    ).run()
    assert ours["close"] == zero["close"] and ours["episodes"] == 2
    assert ours["protocol"]["action_repeat"] == 2 == zero["protocol"]["action_repeat"]
    assert ours["learner"] == "mine" and "learner" not in zero
    assert ours["config"]["env"]["action_repeat"] == 2 and ours["training_seed"] == 4
    assert ours["checkpoint_env_steps"] == 0  # the env took no step


def test_the_policy_acts_and_its_steps_are_recorded(env, tmp_path):
    env.reset()
    for _ in range(3):
        env.step(np.zeros(3))
    path = devlearn.gym.save_policy(Reach(), env, tmp_path / "reach.pt", learner="mine")
    opened = ScriptedPolicy.open(path, REGISTRY, "tiny")
    assert opened.state["env_steps"] == 6  # 3 decisions of 2 physics steps
    position = np.array([0.0, 0.4, 0.9], np.float32)
    action = opened.act({"proprioception": position})
    assert action == pytest.approx(np.clip(5 * (0.5 - position), -1, 1), abs=1e-6)
    summary = run(path)
    assert (
        summary["close"]
        > 0.5
        > run(devlearn.gym.save_policy(Still(), env, path, learner="x"))["close"]
    )
    assert summary["checkpoint_env_steps"] == 6
    assert json.loads(json.dumps(summary))["learner"] == "mine"


def test_what_cannot_be_evaluated_is_one_line(env, tmp_path):
    path = devlearn.gym.save_policy(Still(), env, tmp_path / "policy.pt", learner="mine")
    with pytest.raises(UsageError, match="a scripted policy .* gives one deterministic action"):
        run(path, action="sample")
    with pytest.raises(UsageError, match="is a scripted policy .*: devlearn eval evaluates it"):
        load_checkpoint(path)  # devlearn slim, export, run --from
    other = registry_for(TinyBehavior)
    with pytest.raises(UsageError, match="trained for 'tiny', not 'other'"):
        ScriptedPolicy.open(path, other, "other")
    opened = ScriptedPolicy.open(path, REGISTRY, "tiny")
    with pytest.raises(UsageError, match=r"takes observation 'proprioception' \(3,\).*\(4,\)"):
        opened.act({"proprioception": np.zeros(4, np.float32)})


def test_a_scripted_policy_plays_across_env_workers_as_in_one_env(env, tmp_path):
    """It travels to the workers as its file (TorchScript does not pickle) and acts there as
    it acts here: the episodes of one env playing them in order."""
    path = devlearn.gym.save_policy(Reach(), env, tmp_path / "policy.pt", learner="mine")
    one = run(path)
    spread = run(path, envs=2, workers=2)
    assert spread["execution"]["workers"] == 2
    assert spread["episode_metrics"] == one["episode_metrics"]
    assert spread["close"] == one["close"] and spread["learner"] == "mine"
