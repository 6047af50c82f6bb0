"""Issue #54's learner knobs: the free and squashed heads, orthogonal initialisation, flat
encoders, the activation, observation normalisation and Adam's epsilon, each checked against
what it claims; runs saved before them load as trained."""

from __future__ import annotations

import json
import math

import pytest
import torch
import torch.nn as nn
from test_networks import GROUPS, batch, spec
from tiny_run import config
from torch.distributions import Normal

from devlearn import MLPEncoder, NetworkSpec
from devlearn.api.errors import UsageError
from devlearn.config.run_config import from_dict, learner_spec, to_dict, to_rsl_rl
from devlearn.testing.fake_infant import TinyBehavior
from devlearn.training.distribution import FreeGaussian, SquashedGaussian
from devlearn.training.networks import MultiSenseModel


def test_the_free_head_starts_at_its_spread_and_has_no_bounds():
    dist = FreeGaussian(3, init_std=1.0)
    assert torch.allclose(dist.current_std(), torch.ones(3))
    with torch.no_grad():
        dist.log_std[:] = torch.tensor([-10.0, 0.0, 10.0])
    assert dist.current_std()[0] < 1e-4 and dist.current_std()[2] > 2e4  # nothing clamps it
    dist.update(torch.tensor([[3.0, -0.5, -7.0]]))
    assert torch.equal(dist.deterministic_output(torch.tensor([[3.0, -0.5, -7.0]])),
                       torch.tensor([[1.0, -0.5, -1.0]]))  # fmt: skip


def test_the_squashed_heads_log_probability_is_the_change_of_variables():
    dist = SquashedGaussian(2, init_std=0.7)
    mean = torch.tensor([[0.3, -1.2]])
    dist.update(mean)
    torch.manual_seed(0)
    a = dist.sample()
    assert a.abs().max() < 1.0  # samples never reach the bounds the env would clip at
    u = torch.atanh(a)
    # p_A(a) = p_U(atanh a) / |d tanh/du| = N(u; mean, std) / (1 - a^2)
    expected = (Normal(mean, 0.7).log_prob(u) - torch.log(1 - a**2)).sum(-1)
    assert torch.allclose(dist.log_prob(a), expected, atol=1e-5)
    # a density over (-1, 1): integrates to 1 (one dimension, on a fine grid)
    one = SquashedGaussian(1, init_std=0.7)
    one.update(torch.tensor([[0.3]]))
    grid = torch.linspace(-1 + 1e-6, 1 - 1e-6, 200001).unsqueeze(-1)
    density = one.log_prob(grid).exp().detach()
    assert float(torch.trapezoid(density, grid.squeeze(-1))) == pytest.approx(
        1.0, abs=1e-3
    )
    assert torch.allclose(dist.deterministic_output(mean), torch.tanh(mean))


def test_the_squashed_heads_entropy_falls_as_its_samples_pile_up_at_the_bounds():
    # a Gaussian's entropy grows with the spread for ever; the squashed one's does not: a wide
    # spread only piles the actions up at +-1, which is less spread, not more
    def entropy(std: float) -> float:
        dist = SquashedGaussian(1, init_std=std)
        dist.update(torch.zeros(20000, 1))
        torch.manual_seed(1)
        return float(dist.entropy.mean().detach())

    assert entropy(0.8) > entropy(3.0) > entropy(10.0)


def test_orthogonal_initialisation_has_the_gains_it_claims():
    obs = batch()
    dist = {"class_name": "devlearn.training.distribution:FreeGaussian", "init_std": 1.0}
    torch.manual_seed(0)
    actor = MultiSenseModel(obs, GROUPS, "actor", 4, spec(), distribution_cfg=dist,
                            init="orthogonal")  # fmt: skip
    critic = MultiSenseModel(obs, GROUPS, "critic", 1, spec(), init="orthogonal")
    hidden = actor.encoders["proprioception"][1].weight  # (16, 7): orthonormal columns x sqrt 2
    assert torch.allclose(hidden.T @ hidden, 2.0 * torch.eye(7), atol=1e-5)
    head = [m for m in actor.mlp.modules() if isinstance(m, nn.Linear)][-1].weight  # (4, 16)
    assert torch.allclose(head @ head.T, 1e-4 * torch.eye(4), atol=1e-9)  # gain 0.01
    value = [m for m in critic.mlp.modules() if isinstance(m, nn.Linear)][-1].weight  # (1, 16)
    assert float(value.norm()) == pytest.approx(1.0, abs=1e-5)  # gain 1
    assert all(float(m.bias.abs().max()) == 0.0 for m in actor.modules()
               if isinstance(m, nn.Linear))  # fmt: skip
    with pytest.raises(ValueError, match="valid: torch, orthogonal"):
        MultiSenseModel(obs, GROUPS, "critic", 1, spec(), init="xavier")


def test_flat_encoders_feed_every_observation_to_one_mlp():
    cfg = config("unused", 256, "network.encoders=flat", "network.activation=tanh")
    base = NetworkSpec({"a": MLPEncoder((8,)), "b": MLPEncoder((8,))}, normalize=("a",))
    flat = learner_spec(base, cfg.network)
    obs = {"a": torch.zeros(2, 5), "b": torch.zeros(2, 3, 4)}
    built = {name: enc.build(tuple(obs[name].shape[1:])) for name, enc in flat.encoders.items()}
    assert [built[n](obs[n]).shape[-1] for n in obs] == [5, 12]  # no layers: flattened only
    assert not any(isinstance(m, nn.Linear) for m in built["a"].modules())
    assert flat.normalize == ("a",) and flat.fusion_dims == base.fusion_dims
    every = config("unused", 256, "network.normalize=all", "network.activation=tanh",
                   "network.encoders=behavior")  # fmt: skip
    shaped = learner_spec(base, every.network)
    assert shaped.normalize == ("a", "b")
    layers = shaped.encoders["a"].build((5,))
    assert any(isinstance(m, nn.Tanh) for m in layers) and not any(
        isinstance(m, nn.ReLU) for m in layers
    )
    old = config("unused", 256, "network.encoders=behavior", "network.activation=relu").network
    assert learner_spec(base, old) is base  # issue #28's settings change nothing
    from devlearn.api.sensors import SensorEncoder

    class Eye(SensorEncoder):  # an image's encoder (a CNN) is kept by flat
        def build(self, obs_shape):
            return nn.Flatten()

        def out_dim(self, obs_shape):
            return 4

    eye = Eye()
    with_eye = NetworkSpec({"a": MLPEncoder((8,)), "eyes": eye})
    assert learner_spec(with_eye, cfg.network).encoders["eyes"] is eye


def test_the_knobs_reach_rsl_rl_and_the_optimiser():
    cfg = config("unused", 256, "network.head=squashed", "network.init_std=0.8",
                 "network.init=orthogonal", "ppo.adam_eps=1e-5",
                 "ppo.normalize_advantage_per_mini_batch=true")  # fmt: skip
    train = to_rsl_rl(cfg, TinyBehavior(cfg.behavior))
    assert train["actor"]["distribution_cfg"] == {
        "class_name": "devlearn.training.distribution:SquashedGaussian",
        "init_std": 0.8,
        "final_std": 0.3,  # the default ceiling
        "noise_beta": 1.0,  # pink exploration, the default
        "noise_decision_s": 0.005,  # this config's decision: one physics step
    }
    free = to_rsl_rl(config("unused"), TinyBehavior(cfg.behavior))["actor"]["distribution_cfg"]
    assert free["init_std"] == 1.0 and free["final_std"] == 0.3  # the free head's own start
    assert train["actor"]["init"] == train["critic"]["init"] == "orthogonal"
    assert train["algorithm"]["adam_eps"] == 1e-5
    assert train["algorithm"]["normalize_advantage_per_mini_batch"] is True


@pytest.mark.parametrize(
    ("setting", "message"),
    [
        ("network.head=sb3", "valid: gaussian, paper, free, squashed"),
        ("network.encoders=cnn", "valid: behavior, flat"),
        ("network.init=xavier", "valid: torch, orthogonal"),
        ("network.normalize=some", "valid: behavior, all"),
        ("network.activation=gelu2", "network.activation"),
        ("ppo.adam_eps=0", "ppo.adam_eps must be above 0"),
        ("network.init_std=-1", "network.init_std must be 0"),
    ],
)
def test_a_bad_knob_is_refused_naming_what_is_valid(setting, message):
    with pytest.raises(UsageError, match=message):
        config("unused", 256, setting)


def test_the_valid_activations_are_rsl_rls():
    from rsl_rl.utils import resolve_nn_activation

    from devlearn.config.run_config import ACTIVATIONS

    assert all(resolve_nn_activation(name) is not None for name in ACTIVATIONS)
    with pytest.raises(ValueError):
        resolve_nn_activation("gelu2")


def test_a_run_saved_before_the_knobs_loads_as_it_was_trained():
    knobs = ["network.encoders=flat", "network.init=orthogonal", "network.activation=tanh",
             "ppo.adam_eps=1e-5", "network.init_std=0.9", "network.normalize=all",
             "ppo.normalize_advantage_per_mini_batch=true"]  # fmt: skip
    cfg = config("unused", 256, *knobs)
    saved = to_dict(cfg)
    assert from_dict(saved, TinyBehavior).network == cfg.network  # recorded: kept
    for section, name in [("network", "encoders"), ("network", "init"), ("network", "activation"),
                          ("network", "init_std"), ("network", "normalize"), ("ppo", "adam_eps"),
                          ("ppo", "normalize_advantage_per_mini_batch")]:  # fmt: skip
        del saved[section][name]
    old = from_dict(saved, TinyBehavior)
    assert (old.network.encoders, old.network.init, old.network.activation) == (
        "behavior", "torch", "relu")  # fmt: skip
    assert (old.network.init_std, old.network.normalize) == (0.0, "behavior")
    assert (old.ppo.adam_eps, old.ppo.normalize_advantage_per_mini_batch) == (1e-8, False)
    assert math.isclose(old.ppo.adam_eps, 1e-8)


def test_the_spread_ceiling_falls_from_the_initial_spread_to_the_final_one():
    from devlearn.training.distribution import BoundedGaussian, spread_cap

    assert spread_cap(0.5, 0.05, 0.0) == pytest.approx(0.5)
    assert spread_cap(0.5, 0.05, 0.5) == pytest.approx(math.sqrt(0.5 * 0.05))  # log-linear
    assert spread_cap(0.5, 0.05, 1.0) == pytest.approx(0.05)
    assert spread_cap(0.5, 0.05, 7.0) == pytest.approx(0.05)  # past the run's end: the final
    dist = BoundedGaussian(3, init_std=0.5, min_std=0.05, max_std=1.0, final_std=0.1)
    with torch.no_grad():
        dist.std_param[:] = 1e4  # the learned spread at its upper bound, 1.0
    mean = torch.zeros(2, 3)
    dist.update(mean)
    assert torch.allclose(dist.std, torch.ones(2, 3))  # no ceiling before the run says where
    dist.set_progress(1.0)
    dist.update(mean)
    assert torch.allclose(dist.std, torch.full((2, 3), 0.1))
    free = FreeGaussian(3, init_std=1.0)
    free.set_progress(1.0)  # without final_std: no ceiling
    free.update(mean)
    assert torch.allclose(free.std, torch.ones(2, 3))
    with pytest.raises(ValueError, match="final_std"):
        BoundedGaussian(3, init_std=0.5, final_std=0.6)


def test_a_run_with_a_spread_ceiling_trains_and_its_checkpoint_plays_at_its_steps(tmp_path):
    from tiny_run import factory, registry

    from devlearn.env import BehaviorEnv
    from devlearn.training import train
    from devlearn.training.checkpoint import Checkpoint
    from devlearn.training.distribution import spread_cap

    cfg = config(tmp_path / "run", 256, "network.head=gaussian", "network.init_std=0.5",
                 "network.final_std=0.1")  # fmt: skip
    train(cfg, registry(), infant_factory=factory, progress=False)
    rows = [json.loads(line) for line in (tmp_path / "run" / "metrics.jsonl").open()]
    stds = [r["health/std_max"] for r in rows]
    # each iteration collected under the ceiling of where it started: 0.5 -> 0.1 over 8
    assert stds[0] == pytest.approx(0.5, rel=0.02) and stds[-1] < 0.5 * stds[0]
    for row, std in zip(rows, stds):
        start = (row["step"] - 32) / 256
        assert std <= spread_cap(0.5, 0.1, start) * 1.0001
    opened = Checkpoint.open(tmp_path / "run" / "checkpoint_latest.pt", registry(), "tiny")
    env = BehaviorEnv(opened.behavior(), 0, factory, training=False)
    actor = opened.actor(env.reset(), env.action_dim)
    env.close()
    assert actor.distribution.std_cap == pytest.approx(0.1)  # a finished run: the final spread
    with pytest.raises(UsageError, match="network.final_std must lie in"):
        config("unused", 256, "network.final_std=1.5")  # above the free head's 1.0
    with pytest.raises(UsageError, match="network.final_std must lie in"):
        config("unused", 256, "network.head=gaussian", "network.final_std=0.01")  # < min_std


def test_a_linear_schedule_steps_the_learning_rate_down_to_zero_over_the_run(tmp_path):
    from tiny_run import factory, registry

    from devlearn.training import train
    from devlearn.training.health import HealthWatch

    cfg = config(tmp_path / "run", 256, "ppo.schedule=linear", "ppo.learning_rate=0.001")
    train(cfg, registry(), infant_factory=factory, progress=False)
    rows = [json.loads(line) for line in (tmp_path / "run" / "metrics.jsonl").open()]
    assert len(rows) == 8
    for row in rows:  # each iteration's update used the rate at the steps done before it
        done = (row["step"] - 32) / 256
        assert row["learning_rate"] == pytest.approx(0.001 * (1 - done))
    assert rows[-1]["learning_rate"] == pytest.approx(0.001 / 8)
    # the adaptive schedule's floor is its "stalled" signature; a linear rate goes below it
    watch = HealthWatch((0.05, 1.0), adaptive=False)
    for _ in range(30):
        assert not watch.check({"loss/surrogate": 0.1, "learning_rate": 1e-7})
    with pytest.raises(UsageError, match="ppo.schedule must be one of fixed, adaptive, linear"):
        config("unused", 256, "ppo.schedule=cosine")


def test_a_linear_schedule_with_a_decay_share_holds_the_rate_then_falls_over_the_runs_end(
    tmp_path,
):
    from tiny_run import factory, registry

    from devlearn.training import train

    cfg = config(
        tmp_path / "run", 256, "ppo.schedule=linear", "ppo.learning_rate=0.001",
        "ppo.decay_share=0.25",
    )  # fmt: skip
    train(cfg, registry(), infant_factory=factory, progress=False)
    rows = [json.loads(line) for line in (tmp_path / "run" / "metrics.jsonl").open()]
    rates = [row["learning_rate"] for row in rows]  # 8 iterations of 32 steps
    # held until 75% of the steps are done (iteration 7 starts there), then half at 87.5%
    assert rates == pytest.approx([0.001] * 7 + [0.0005])
    for bad in ("0", "1.5"):
        with pytest.raises(UsageError, match="ppo.decay_share must be above 0 and at most 1"):
            config("unused", 256, "ppo.schedule=linear", f"ppo.decay_share={bad}")


def test_a_run_longer_than_full_rate_steps_takes_a_smaller_step_size(tmp_path):
    """Issue #54 item 2: the step size is ``learning_rate`` up to ``ppo.full_rate_steps``, then
    falls as 1/steps to half at twice as many, and stays there; every schedule starts from it,
    a resume keeps it, and 0 (saved runs, hand regard) keeps ``learning_rate`` for any run."""
    from tiny_run import factory, registry

    from devlearn.config.run_config import PPOConfig
    from devlearn.training import train

    ppo = PPOConfig(learning_rate=0.002, full_rate_steps=100)
    assert [ppo.run_rate(n) for n in (50, 100, 125, 200, 10_000)] == pytest.approx(
        [0.002, 0.002, 0.0016, 0.001, 0.001]
    )
    assert ppo.linear_rate(0, 125) == pytest.approx(0.0016)  # the linear schedule's start
    assert PPOConfig(learning_rate=3e-4).run_rate(2_048_000) == 1.5e-4  # half_lr's, bit for bit
    assert PPOConfig(learning_rate=0.002, full_rate_steps=0).run_rate(10_000) == 0.002
    # a tiny run of 192 steps with full_rate_steps=128: 128/192 of the step size in every update
    fixed = ("ppo.schedule=fixed", "ppo.learning_rate=0.002", "ppo.full_rate_steps=128")
    cfg = config(tmp_path / "run", 192, *fixed)
    assert to_rsl_rl(cfg, TinyBehavior())["algorithm"]["learning_rate"] == 0.002 * 128 / 192
    train(cfg, registry(), infant_factory=factory, progress=False)
    rows = [json.loads(line) for line in (tmp_path / "run" / "metrics.jsonl").open()]
    assert [row["learning_rate"] for row in rows] == pytest.approx([0.002 * 128 / 192] * 6)
    resumed = config(tmp_path / "run", 256, *fixed)  # resumed with a longer budget: its rate
    train(resumed, registry(), resume=tmp_path / "run", infant_factory=factory, progress=False)
    rows = [json.loads(line) for line in (tmp_path / "run" / "metrics.jsonl").open()]
    assert [row["learning_rate"] for row in rows[6:]] == pytest.approx([0.001] * 2)
    # below the full-rate budget, the configured rate as before
    short = config("unused", 64, *fixed)
    assert to_rsl_rl(short, TinyBehavior())["algorithm"]["learning_rate"] == 0.002
    with pytest.raises(UsageError, match="ppo.full_rate_steps must be at least 0"):
        config("unused", 256, "ppo.full_rate_steps=-1")


def test_pink_exploration_keeps_the_policys_law_and_correlates_its_draws():
    """Issue #54 item 3: ``network.exploration_beta`` samples mean + std * coloured noise. Each
    draw must still be the policy's Gaussian (mean, std: PPO's probabilities are computed with
    it), successive draws must be correlated (white noise's are not), and beta 0 must sample
    exactly as before (saved runs replay)."""
    torch.manual_seed(0)
    pink = FreeGaussian(2, init_std=1.0, noise_beta=1.0, noise_decision_s=0.025)
    mean, std = torch.tensor([[0.5, -0.2]]).repeat(64, 1), torch.tensor([0.3, 0.1])
    with torch.no_grad():
        pink.log_std[:] = std.log()
    draws = []
    for _ in range(3000):
        pink.update(mean)
        draws.append(pink.sample())
    x = torch.stack(draws)  # (time, envs, actions)
    assert torch.allclose(x.mean(dim=(0, 1)), mean[0], atol=0.03)
    assert torch.allclose(x.std(dim=(0, 1)), std, rtol=0.1)
    z = (x - mean) / std
    assert float((z[1:] * z[:-1]).mean()) > 0.5  # pink: neighbours alike
    white = FreeGaussian(2, init_std=1.0)
    torch.manual_seed(1)
    w = []
    for _ in range(3000):
        white.update(mean)
        w.append(white.sample())
    zw = (torch.stack(w) - mean) / 1.0
    assert abs(float((zw[1:] * zw[:-1]).mean())) < 0.05  # white: neighbours independent
    # beta 0 draws exactly what the Normal draws (runs saved before the option replay)
    torch.manual_seed(2)
    white.update(mean)
    a = white.sample()
    torch.manual_seed(2)
    assert torch.equal(a, Normal(mean, torch.ones(2)).sample())
    # a new batch size (an evaluation's envs) starts its own streams
    pink.update(mean[:3])
    assert pink.sample().shape == (3, 2)


def test_the_squashed_head_explores_with_the_coloured_noise_too():
    """``network.exploration_beta`` holds for every head: the squashed head's draws (tanh of
    the Gaussian's) are correlated over decisions, not white."""
    torch.manual_seed(0)
    head = SquashedGaussian(2, init_std=1.0, noise_beta=1.0, noise_decision_s=0.025)
    mean = torch.zeros(64, 2)
    with torch.no_grad():
        head.log_std[:] = math.log(0.3)
    draws = []
    for _ in range(2000):
        head.update(mean)
        draws.append(torch.atanh(head.sample()) / 0.3)
    z = torch.stack(draws)
    assert float((z[1:] * z[:-1]).mean()) > 0.5  # pink: neighbours alike (white: ~0)


def test_exploration_beta_reaches_the_head_and_is_checked():
    cfg = config("unused", 256, "network.exploration_beta=1", "env.action_repeat=5")
    dist = to_rsl_rl(cfg, TinyBehavior(cfg.behavior))["actor"]["distribution_cfg"]
    assert dist["noise_beta"] == 1.0 and dist["noise_decision_s"] == pytest.approx(0.025)
    assert config("unused", 256).network.exploration_beta == 1.0  # pink: the default
    white = config("unused", 256, "network.exploration_beta=0")
    assert "noise_beta" not in to_rsl_rl(white, TinyBehavior(white.behavior))["actor"][
        "distribution_cfg"
    ]
    with pytest.raises(UsageError, match="exploration_beta must be from 0"):
        config("unused", 256, "network.exploration_beta=2")
