"""MultiSenseModel, TanhSoftplusGaussian and the unique-parameter PPO optimiser."""

from __future__ import annotations

import io

import pytest
import torch
import torch.nn as nn
from rsl_rl.storage import RolloutStorage
from tensordict import TensorDict

from devlearn import MLPEncoder, NetworkSpec
from devlearn.training.networks import MultiSenseModel, TanhSoftplusGaussian
from devlearn.training.ppo import UniqueParamPPO, unique_parameters

GROUPS = {"actor": ["proprioception", "eyes"], "critic": ["proprioception", "eyes"]}
DIST = {"class_name": "devlearn.training.networks:TanhSoftplusGaussian", "init_std": 0.3}


def batch(n: int = 5) -> TensorDict:
    gen = torch.Generator().manual_seed(0)
    return TensorDict(
        {
            "proprioception": torch.randn(n, 7, generator=gen),
            "eyes": torch.randint(0, 256, (n, 2, 8, 8, 3), generator=gen, dtype=torch.uint8),
        },
        batch_size=[n],
    )


def spec() -> NetworkSpec:
    encoders = {"proprioception": MLPEncoder((16,)), "eyes": MLPEncoder((12,))}
    return NetworkSpec(encoders, fusion_dims=(32,), trunk_dims=(16, 16), init_std=0.3)


def actor_critic():
    obs = batch()
    torch.manual_seed(0)
    actor = MultiSenseModel(obs, GROUPS, "actor", 4, spec(), distribution_cfg=DIST)
    critic = MultiSenseModel(obs, GROUPS, "critic", 1, spec())
    return obs, actor, critic


def test_shapes_and_multidimensional_groups():
    obs, actor, critic = actor_critic()
    assert actor.obs_shapes == {"proprioception": (7,), "eyes": (2, 8, 8, 3)}
    assert actor.get_latent(obs).shape == (5, 16 + 12)
    assert actor(obs).shape == (5, 4)
    assert actor(obs, stochastic_output=True).shape == (5, 4)
    assert critic(obs).shape == (5, 1)
    # (fusion 32) + (trunk 16, 16) + head (2, 4)
    linears = [m for m in actor.mlp if isinstance(m, nn.Linear)]
    assert [m.out_features for m in linears] == [32, 16, 16, 8]


def test_missing_encoder_is_named():
    obs = batch()
    partial = NetworkSpec({"proprioception": MLPEncoder((8,))}, (8,), (8,))
    with pytest.raises(ValueError, match=r"\['eyes'\].*no encoder"):
        MultiSenseModel(obs, GROUPS, "actor", 4, partial)


def test_tanh_mean_bounded_and_std_positive():
    obs, actor, _ = actor_critic()
    actor(obs, stochastic_output=True)
    torch.testing.assert_close(actor.output_std, torch.full((5, 4), 0.3), atol=0.02, rtol=0)
    with torch.no_grad():  # blow the head up: the mean saturates, the std stays positive
        head = actor.mlp[-2]
        head.weight.mul_(1e4)
        head.bias[4:].fill_(-1e4)
    actor(obs, stochastic_output=True)
    assert actor.output_mean.abs().max() <= 1.0
    assert actor.output_mean.abs().max() > 0.99
    assert torch.all(actor.output_std > 0)
    assert torch.all(torch.isfinite(actor.get_output_log_prob(actor(obs, stochastic_output=True))))
    torch.testing.assert_close(actor(obs), actor.output_mean)  # deterministic output = mean


def test_std_is_state_dependent():
    dist = TanhSoftplusGaussian(2, init_std=0.5)
    raw = torch.tensor([[[0.0, 0.0], [0.0, 0.0]], [[0.0, 0.0], [3.0, -3.0]]])
    dist.update(raw)
    assert not torch.allclose(dist.std[0], dist.std[1])
    assert torch.all(dist.kl_divergence(dist.params, dist.params).abs() < 1e-6)


def test_save_load_round_trip():
    obs, actor, _ = actor_critic()
    buffer = io.BytesIO()
    torch.save(actor.state_dict(), buffer)
    torch.manual_seed(123)
    other = MultiSenseModel(obs, GROUPS, "actor", 4, spec(), distribution_cfg=DIST)
    assert not torch.allclose(other(obs), actor(obs))
    buffer.seek(0)
    other.load_state_dict(torch.load(buffer))
    torch.testing.assert_close(other(obs), actor(obs))


def test_actor_and_critic_share_no_parameters():
    _, actor, critic = actor_critic()
    assert not {id(p) for p in actor.parameters()} & {id(p) for p in critic.parameters()}


def test_optimiser_holds_shared_parameters_once():
    obs, actor, critic = actor_critic()
    critic.encoders = actor.encoders  # share the encoders, as rsl-rl's share_cnn_encoders does
    storage = RolloutStorage("rl", 5, 2, obs, [4])
    ppo = UniqueParamPPO(actor, critic, storage, learning_rate=0.1)
    params = [p for group in ppo.optimizer.param_groups for p in group["params"]]
    assert len(params) == len({id(p) for p in params}) == len(unique_parameters(actor, critic))
    shared = actor.encoders["proprioception"][1].weight
    before = shared.detach().clone()
    loss = actor(obs).sum() + critic(obs).sum()
    ppo.optimizer.zero_grad()
    loss.backward()
    ppo.optimizer.step()
    # Adam's first step moves every weight with a gradient by lr (0.1), not twice that
    moved = (shared.detach() - before).abs()
    changed = moved > 0
    torch.testing.assert_close(moved[changed], torch.full_like(moved[changed], 0.1))


def test_max_std_bounds_the_spread_and_starts_at_init_std():
    raw_huge = torch.tensor([[[0.0, 0.0], [50.0, -50.0]]])
    unbounded = TanhSoftplusGaussian(2, init_std=0.5)
    unbounded.update(raw_huge)
    assert unbounded.std[0, 0] > 49  # softplus: the paper's spread has no ceiling
    bounded = TanhSoftplusGaussian(2, init_std=0.5, max_std=1.0)
    bounded.update(raw_huge)
    assert bounded.std.max() <= 1.0 and bounded.std.min() > 0
    obs = batch()
    torch.manual_seed(0)
    actor = MultiSenseModel(obs, GROUPS, "actor", 4, spec(), distribution_cfg={**DIST, "max_std": 1.0})
    actor(obs, stochastic_output=True)
    torch.testing.assert_close(actor.output_std, torch.full((5, 4), 0.3), atol=0.02, rtol=0)
    with pytest.raises(ValueError, match="max_std must be 0 \\(unbounded\\) or above init_std=0.5"):
        TanhSoftplusGaussian(2, init_std=0.5, max_std=0.4)


@pytest.mark.parametrize("max_std", [-1.0, 0.2, 0.3])
def test_network_spec_rejects_a_spread_bound_not_above_the_initial_spread(max_std):
    """One check in the core, so no behaviour need repeat it (or forget it)."""
    with pytest.raises(ValueError, match="max_std must be 0 \\(unbounded\\) or above init_std=0.3"):
        NetworkSpec({"proprioception": MLPEncoder((8,))}, init_std=0.3, max_std=max_std)
    with pytest.raises(ValueError, match="init_std must exceed min_std"):
        NetworkSpec({"proprioception": MLPEncoder((8,))}, init_std=0.0)
    assert NetworkSpec({"proprioception": MLPEncoder((8,))}, init_std=0.3, max_std=0.0).max_std == 0.0
