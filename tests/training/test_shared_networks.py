"""The shared actor/critic layout: one body, two heads, each parameter stepped once."""

from __future__ import annotations

import dataclasses
import importlib
from functools import partial
from types import SimpleNamespace

import pytest
import tiny_run
import torch
from rsl_rl.algorithms import PPO
from tensordict import TensorDict

from devlearn.api.errors import UsageError
from devlearn.config.run_config import from_dict, to_dict, to_rsl_rl
from devlearn.testing.fake_infant import TinyBehavior
from devlearn.training.ppo import UniqueParamPPO, unique_parameters
from devlearn.training.process import quiet

EPOCHS, MINI_BATCHES, ENVS, STEPS = 2, 3, 4, 6


class NormalisedTiny(TinyBehavior):
    def network(self):
        return dataclasses.replace(super().network(), normalize=("proprioception",))


def build(layout: str, algorithm=UniqueParamPPO, behavior_cls=TinyBehavior):
    """A PPO learner for the tiny behaviour, built the way the runner builds it."""
    cfg = tiny_run.config(
        "unused",
        64,
        f"network.layout={layout}",
        f"ppo.num_learning_epochs={EPOCHS}",
        f"ppo.num_mini_batches={MINI_BATCHES}",
        f"ppo.num_steps_per_env={STEPS}",
    )
    behavior = behavior_cls(cfg.behavior)
    train_cfg = to_rsl_rl(cfg, behavior)
    train_cfg["multi_gpu"] = None
    if algorithm is not UniqueParamPPO:
        train_cfg["algorithm"]["class_name"] = algorithm
        train_cfg["algorithm"].pop("adam_eps")  # ours (UniqueParamPPO's), not rsl-rl's
    gen = torch.Generator().manual_seed(0)

    def observations() -> TensorDict:
        return TensorDict({"proprioception": torch.randn(ENVS, 3, generator=gen)}, [ENVS])

    env = SimpleNamespace(num_envs=ENVS, num_actions=2, unwrapped=SimpleNamespace(step_dt=0.1))
    torch.manual_seed(0)
    with quiet():
        alg = algorithm.construct_algorithm(observations(), env, train_cfg, "cpu")
    return alg, observations


def fill(alg, observations) -> None:
    with torch.inference_mode():
        obs = observations()
        for _ in range(STEPS):
            alg.act(obs)
            obs = observations()
            dones = torch.zeros(ENVS, dtype=torch.long)
            alg.process_env_step(obs, torch.randn(ENVS), dones, {"time_outs": torch.zeros(ENVS)})
        alg.compute_returns(obs)


def test_shared_layout_has_one_body_and_two_heads():
    alg, _ = build("shared")
    actor, critic = alg.actor, alg.critic
    assert critic.cnns is actor.body
    assert not {id(p) for p in actor.parameters()} & {id(p) for p in critic.parameters()}
    assert [tuple(p.shape) for p in critic.parameters()] == [(1, actor.body.out_dim), (1,)]
    separate, _ = build("separate")
    assert separate.critic.cnns is None
    assert sum(p.numel() for p in unique_parameters(alg.actor, alg.critic)) < sum(
        p.numel() for p in unique_parameters(separate.actor, separate.critic)
    )


@pytest.mark.parametrize("algorithm", [UniqueParamPPO, PPO])
@pytest.mark.parametrize("layout", ["shared", "separate"])
def test_every_parameter_is_stepped_once_per_mini_batch(layout, algorithm):
    alg, observations = build(layout, algorithm)
    fill(alg, observations)
    alg.update()
    params = unique_parameters(alg.actor, alg.critic)
    steps = [int(alg.optimizer.state[p]["step"]) for p in params]
    assert steps == [EPOCHS * MINI_BATCHES] * len(params)


def test_the_step_count_catches_a_parameter_listed_twice():
    """The check above can fail: a body listed under both networks gets two Adam steps."""
    alg, observations = build("shared", PPO)
    body = list(alg.actor.body.parameters())
    alg.optimizer = torch.optim.Adam(list(alg.actor.parameters()) + body, lr=1e-3)
    fill(alg, observations)
    alg.update()
    assert int(alg.optimizer.state[body[0]]["step"]) == 2 * EPOCHS * MINI_BATCHES


def test_body_runs_once_per_batch_and_gradients_are_those_of_two_passes():
    alg, observations = build("shared")
    calls = []
    alg.actor.body.trunk.register_forward_hook(lambda *args: calls.append(1))
    fill(alg, observations)
    assert len(calls) == STEPS + 1  # act (actor, critic, critic) once; the last value once
    calls.clear()
    alg.update()
    assert len(calls) == EPOCHS * MINI_BATCHES
    # the reused features give the gradients of separate forward passes
    obs = observations()
    actor, critic = alg.actor, alg.critic
    grads = []
    for same_object in (True, False):
        alg.optimizer.zero_grad()
        loss = actor(obs).sum() + critic(obs if same_object else obs.clone()).sum()
        loss.backward()
        grads.append([p.grad.clone() for p in actor.body.parameters()])
    for cached, fresh in zip(*grads):
        torch.testing.assert_close(cached, fresh)


def test_shared_normaliser_counts_each_rollout_once():
    alg, observations = build("shared", behavior_cls=NormalisedTiny)
    fill(alg, observations)
    alg.update()
    (normalizer,) = alg.actor.body.normalizers.values()
    assert int(normalizer.count) == ENVS * STEPS


def test_layout_is_recorded_and_old_configs_mean_the_old_layout():
    cfg = tiny_run.config("unused")
    assert cfg.network.layout == "shared"  # NetworkSpec.share's default, written down
    assert cfg.network.legacy_uint8_scale is False
    data = to_dict(cfg)
    assert from_dict(data, TinyBehavior).network == cfg.network
    del data["network"]  # a config.json from before the shared layout
    old = from_dict(data, TinyBehavior)
    assert old.network.layout == "separate" and old.network.legacy_uint8_scale is True
    old.network.layout = "tied"
    with pytest.raises(UsageError, match="unknown network.layout 'tied'; valid: shared"):
        to_rsl_rl(old, TinyBehavior(old.behavior))


def test_rsl_rl_rnd_trains_and_logs_its_intrinsic_reward(tmp_path, monkeypatch):
    """The runner passes rsl-rl's intrinsic rewards to its logger (None made its log fail)."""
    train_module = importlib.import_module("devlearn.training.train")

    def with_rnd(cfg, behavior, names=None):
        train_cfg = to_rsl_rl(cfg, behavior, names)
        train_cfg["obs_groups"]["rnd_state"] = ["proprioception"]
        train_cfg["algorithm"]["rnd_cfg"] = {
            "num_outputs": 4,
            "predictor_hidden_dims": [8],
            "target_hidden_dims": [8],
            "weight": 1.0,
        }
        return train_cfg

    monkeypatch.setattr(train_module, "to_rsl_rl", with_rnd)
    cfg = tiny_run.config(tmp_path / "run", 96)  # 3 iterations of 32 steps, 10-step episodes
    result = train_module.train(
        cfg, tiny_run.registry(), infant_factory=tiny_run.factory, progress=False
    )
    assert result.iterations == 3 and result.last["loss/rnd"] > 0


def test_features_are_not_reused_after_the_normaliser_moved():
    alg, observations = build("shared", behavior_cls=NormalisedTiny)
    obs = observations()
    with torch.inference_mode():
        before = alg.actor.get_latent(obs)
        alg.actor.train()
        alg.actor.update_normalization(
            TensorDict({"proprioception": 5 + obs["proprioception"]}, [ENVS])
        )
        after = alg.critic.get_latent(obs)
    assert not torch.allclose(before, after)


def observation_batch(gen: torch.Generator) -> TensorDict:
    return TensorDict({"proprioception": torch.randn(ENVS, 3, generator=gen)}, [ENVS])


def test_multi_tensor_adam_steps_the_parameters_bit_for_bit_and_survives_a_resume():
    """The optimiser's multi-tensor (foreach) steps give the same parameters as torch's
    one-tensor-at-a-time default (which results were recorded with), and loading a state
    saved without them (``foreach: None``) keeps them."""
    alg, _ = build("separate")
    assert all(group["foreach"] for group in alg.optimizer.param_groups)
    single, _ = build("separate")
    params = unique_parameters(single.actor, single.critic)
    eps = alg.optimizer.param_groups[0]["eps"]
    single.optimizer = torch.optim.Adam(params, lr=single.learning_rate, eps=eps)
    for learner in (alg, single):  # the same observations and action noise for both
        gen = torch.Generator().manual_seed(1)
        torch.manual_seed(2)
        for _ in range(2):
            fill(learner, partial(observation_batch, gen))
            learner.update()
    for ours, theirs in zip(unique_parameters(alg.actor, alg.critic), params):
        assert torch.equal(ours, theirs)
    saved = single.save()
    assert saved["optimizer_state_dict"]["param_groups"][0]["foreach"] is None
    alg.load(saved, None, strict=True)
    assert all(group["foreach"] for group in alg.optimizer.param_groups)
