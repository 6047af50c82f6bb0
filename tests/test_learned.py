"""The LearnedReward kind: weight schedule, reward scale, conformance check, registration."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from fake_plugins import fake_plugin
from learned_terms import ForgetfulPredictor, LinearConfig, LinearPredictor

from devlearn.api.errors import UsageError
from devlearn.api.learned import LearnedReward
from devlearn.api.learned_update import RunningScale
from devlearn.plugins import PluginRegistry, PluginSource
from devlearn.testing import ConformanceError, check_learned_reward

SHAPES = {"proprioception": (6,)}


def term(**options) -> LinearPredictor:
    return LinearPredictor(LinearConfig(**options), SHAPES, 3)


def test_weight_schedules_constant_linear_and_step():
    assert [term(weight=0.3).weight_at(s) for s in (0, 10**9)] == [0.3, 0.3]
    linear = term(weight=1.0, final_weight=0.0, schedule_start=100, schedule_end=300)
    assert [linear.weight_at(s) for s in (0, 100, 200, 300, 400)] == [1.0, 1.0, 0.5, 0.0, 0.0]
    step = term(weight=0.0, final_weight=2.0, schedule_start=50, schedule_end=50)
    assert [step.weight_at(s) for s in (49, 50)] == [0.0, 2.0]


def test_config_checks_its_values():
    with pytest.raises(ValueError, match="mini_batches"):
        LinearConfig(mini_batches=0)
    with pytest.raises(ValueError, match="schedule_end"):
        LinearConfig(final_weight=0.0, schedule_start=10, schedule_end=5)


def test_running_scale_is_the_std_of_everything_seen():
    scale = RunningScale()
    rng = np.random.default_rng(0)
    chunks = [rng.normal(3.0, 2.0, n) for n in (5, 50, 1, 200)]
    for chunk in chunks:
        scale.update(torch.as_tensor(chunk))
    assert scale.std == pytest.approx(np.concatenate(chunks).std(), rel=1e-9)
    assert float(scale(torch.tensor([scale.std]))) == pytest.approx(1.0)


def test_update_normalises_and_weights_the_reward():
    t = term(weight=0.5, final_weight=None)
    check = check_learned_reward(LinearPredictor, SHAPES)  # also a conformance pass
    assert isinstance(check, LearnedReward)
    from devlearn.testing.learned import random_transitions as _random_transitions

    batch = _random_transitions(SHAPES, 3, 64, seed=0)
    with torch.no_grad():
        raw = t.compute_reward(batch)
    reward, log = t.update(batch, env_steps=0)
    torch.testing.assert_close(reward, 0.5 * raw / raw.double().std(unbiased=False).float())
    assert log["raw"] == pytest.approx(float(raw.mean())) and log["weight"] == 0.5
    assert t.updates == 1


def test_conformance_catches_a_term_that_forgets_its_optimiser():
    with pytest.raises(ConformanceError, match="trains differently"):
        check_learned_reward(ForgetfulPredictor, SHAPES)


def _plugin(name: str, *terms) -> PluginSource:
    return fake_plugin(name, "register_learned_rewards", *terms)


def test_registry_finds_learned_rewards_and_reports_clashes():
    registry = PluginRegistry([_plugin("a", LinearPredictor), _plugin("b", LinearPredictor)])
    assert registry.learned_rewards() == {"linear": LinearPredictor}
    assert registry.plugins["a"].learned_rewards == ["linear"]
    assert registry.plugins["a"].hooks == ["register_learned_rewards"]
    assert any("'linear' is already registered by plugin 'a'" in e for e in registry.errors)
    with pytest.raises(UsageError, match="unknown learned reward 'lineer'; installed: linear"):
        registry.learned_reward("lineer")


def test_registry_rejects_what_is_not_a_learned_reward():
    registry = PluginRegistry([_plugin("bad", dict), _plugin("good", LinearPredictor)])
    assert registry.plugins["bad"].error and "not a LearnedReward" in registry.plugins["bad"].error
    assert list(registry.learned_rewards()) == ["linear"]
