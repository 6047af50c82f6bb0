"""Issue #28's learner: reward normalisation, a head that cannot saturate, health warnings,
and old checkpoints' configs loading as trained."""

from __future__ import annotations

import numpy as np
import pytest
import tiny_run
import torch

from devlearn.api.errors import UsageError
from devlearn.config.run_config import from_dict, to_dict
from devlearn.testing import run_config
from devlearn.testing.fake_infant import TinyBehavior
from devlearn.training.distribution import BoundedGaussian, TanhSoftplusGaussian, inverse_softplus
from devlearn.training.health import PATIENCE, HealthWatch, rollout_health
from devlearn.training.reward_norm import RewardNormalizer, RunningMoments

# --- reward normalisation ---------------------------------------------------------------


def reference_normalised(rewards, dones, gamma, clip, eps=1e-8):
    """SB3's VecNormalize on rewards, written out plainly: per-env discounted returns (reset
    after an episode's last step), the variance of every return seen so far, r / sqrt(var)."""
    returns = np.zeros(rewards.shape[1])
    seen: list[float] = []
    out = np.zeros_like(rewards)
    for t in range(len(rewards)):
        returns = returns * gamma + rewards[t]
        seen.extend(returns)
        out[t] = np.clip(rewards[t] / np.sqrt(np.var(seen) + eps), -clip, clip)
        returns[dones[t]] = 0.0
    return out


def test_reward_normalisation_matches_the_definition_on_a_recorded_sequence():
    rng = np.random.default_rng(0)
    steps, envs, gamma = 40, 3, 0.9
    rewards = rng.normal(2.0, 3.0, (steps, envs))  # a scale far from 1, non-zero mean
    dones = np.zeros((steps, envs), dtype=bool)
    dones[[9, 19, 29, 39], 0] = True  # env 0: episodes of 10 steps
    dones[[14, 39], 1] = True  # env 1: 15, then 25
    dones[[4, 7, 20], 2] = True
    norm = RewardNormalizer(envs, gamma, clip=10.0)
    got = np.stack(
        [
            norm(torch.tensor(r, dtype=torch.float32), torch.tensor(d)).numpy()
            for r, d in zip(rewards, dones)
        ]
    )
    want = reference_normalised(rewards, dones, gamma, 10.0)
    np.testing.assert_allclose(got, want, rtol=2e-4, atol=1e-5)
    # a return that never resets would give other numbers: the episode ends matter
    assert not np.allclose(want, reference_normalised(rewards, dones & False, gamma, 10.0))


def test_reward_normalisation_clips_and_its_state_round_trips():
    norm = RewardNormalizer(2, 0.99, clip=0.5)
    for _ in range(5):
        norm(torch.tensor([1.0, -1.0]), torch.tensor([False, False]))
    assert norm(torch.tensor([1e6, -1e6]), torch.tensor([True, False])).tolist() == [0.5, -0.5]
    copy = RewardNormalizer(2, 0.99, clip=0.5)
    copy.load_state_dict(norm.state_dict())
    assert copy.std == norm.std
    assert torch.equal(copy.returns, norm.returns) and copy.returns[0] == 0.0


def test_reward_moments_are_rsl_rls_bit_for_bit_and_load_its_saved_state():
    """Issue #59: the running moments are our own (no private rsl-rl attribute read), with
    rsl-rl's arithmetic and state layout: a checkpoint saved when EmpiricalNormalization held
    them resumes exactly."""
    from rsl_rl.modules import EmpiricalNormalization

    torch.manual_seed(0)
    ours, theirs = RunningMoments(), EmpiricalNormalization(1, eps=0.0)
    for rows in (3, 3, 1, 8, 3):
        x = torch.randn(rows, 1) * 4.0 + 2.0
        ours.update(x)
        theirs.update(x)
    assert ours.state_dict().keys() == theirs.state_dict().keys()
    for key, value in theirs.state_dict().items():
        assert torch.equal(ours.state_dict()[key], value), key
    assert torch.equal(ours.var, ours.state_dict()["_var"].squeeze())
    # a normaliser saved with rsl-rl's moments (the checkpoint format before issue #59) loads
    saved = RewardNormalizer(2, 0.9)
    saved.moments = EmpiricalNormalization(1, eps=0.0)
    saved.moments.update(torch.tensor([[1.0], [5.0], [-2.0]]))
    resumed = RewardNormalizer(2, 0.9)
    resumed.load_state_dict(saved.state_dict())
    assert resumed.std == float(torch.sqrt(saved.moments._var.squeeze() + 1e-8))
    assert resumed.moments.count == 3


# --- the policy head ------------------------------------------------------------------


def bandit_pre_activation(dist, iterations: int = 300) -> float:
    """Policy gradient (normalised advantages, Adam) on a one-step bandit whose reward rises
    up to the action bound: r = clip(a, -1, 1). Returns the mean's pre-activation at the end
    (the tanh head's raw mean; the bounded head's mean itself)."""
    torch.manual_seed(0)
    paper = isinstance(dist, TanhSoftplusGaussian)
    shape = [2, 1] if paper else [1]
    raw = torch.nn.Parameter(torch.zeros(shape))
    if paper:
        with torch.no_grad():
            raw[1, 0] = inverse_softplus(0.5 - 1e-3)  # the same initial spread, 0.5
    opt = torch.optim.Adam([raw, *dist.parameters()], lr=0.05)
    for _ in range(iterations):
        dist.update(raw.expand(256, *shape))
        with torch.no_grad():
            actions = dist.sample()
            reward = actions.clamp(-1, 1).sum(-1)
            adv = (reward - reward.mean()) / (reward.std() + 1e-8)
        loss = -(dist.log_prob(actions) * adv).mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
    return float((raw[0, 0] if paper else raw[0]).detach())


def test_the_paper_head_saturates_on_a_bandit_and_the_bounded_head_does_not():
    paper_raw = bandit_pre_activation(TanhSoftplusGaussian(1, init_std=0.5))
    bounded = bandit_pre_activation(BoundedGaussian(1, init_std=0.5))
    # tanh mean: half the samples always fall below the mean (< 1), so the pre-activation
    # keeps climbing: deep in saturation after 300 steps, and still rising with more
    assert paper_raw > 3.0
    assert bandit_pre_activation(TanhSoftplusGaussian(1, init_std=0.5), 900) > paper_raw + 0.5
    # linear mean: once almost no sample falls inside [-1, 1] the push stops, a few spreads
    # past the bound (max_std 1.0); the action it takes is the bound
    assert 1.0 <= bounded < 1.0 + 5 * 1.0
    assert bandit_pre_activation(BoundedGaussian(1, init_std=0.5), 900) == pytest.approx(bounded)


def test_the_bounded_head_keeps_its_spread_within_its_bounds():
    dist = BoundedGaussian(4, init_std=0.5, min_std=0.05, max_std=1.0)
    assert torch.allclose(dist.current_std(), torch.full((4,), 0.5))
    with torch.no_grad():
        dist.std_param[:2] = 1e4
        dist.std_param[2:] = -1e4
    std = dist.current_std()
    assert torch.allclose(std[:2], torch.full((2,), 1.0)) and torch.allclose(
        std[2:], torch.full((2,), 0.05)
    )
    with pytest.raises(ValueError, match="min_std < init_std < max_std"):
        BoundedGaussian(2, init_std=2.0, max_std=1.0)


def test_head_option_is_checked_and_old_configs_load_as_trained():
    cfg = tiny_run.config("unused")
    assert (cfg.network.head, cfg.ppo.normalize_rewards) == ("free", True)
    with pytest.raises(UsageError, match="valid: gaussian, paper"):
        tiny_run.config("unused", 256, "network.head=tanh")
    with pytest.raises(UsageError, match="env.action_repeat"):
        tiny_run.config("unused", 256, "env.action_repeat=0")
    saved = to_dict(cfg)
    del saved["network"]["head"], saved["ppo"]["normalize_rewards"]
    old = from_dict(saved, TinyBehavior)  # a run from before issue #28
    assert (old.network.head, old.ppo.normalize_rewards) == ("paper", False)
    assert from_dict(to_dict(cfg), TinyBehavior).network.head == "free"


# --- learner health ---------------------------------------------------------------------


class _Storage:
    def __init__(self, mean, std, returns, values):
        self.distribution_params = (mean, std)
        self.returns, self.values = returns, values


def test_rollout_health_figures():
    mean = torch.tensor([[[0.0, 1.2]], [[0.5, -0.999]]])  # (T=2, N=1, A=2)
    std = torch.tensor([[[0.1, 0.3]], [[0.3, 0.5]]])
    returns = torch.tensor([[[1.0]], [[3.0]]])
    h = rollout_health(_Storage(mean, std, returns, returns * 0.5))
    assert h["health/std_min"] == pytest.approx(0.2) and h["health/std_max"] == pytest.approx(0.4)
    assert h["health/saturated"] == pytest.approx(0.5)  # 1.2 and -0.999 of 4
    # 1 - var(returns - values) / var(returns) = 1 - var([0.5, 1.5]) / var([1, 3]) = 0.75
    assert h["health/explained_variance"] == pytest.approx(0.75)


def test_health_watch_warns_once_after_a_lasting_collapse_signature():
    watch = HealthWatch((0.05, 1.0))
    stalled = {"loss/surrogate": 0.001, "learning_rate": 1e-5, "health/std_mean": 0.5}
    healthy = {"loss/surrogate": -0.02, "learning_rate": 3e-4, "health/std_mean": 0.5}
    for _ in range(PATIENCE - 1):
        assert watch.check(stalled) == []
    assert watch.check(healthy) == []  # a break starts the count again
    said = [w for _ in range(PATIENCE + 5) for w in watch.check({**stalled, "step": 7})]
    assert len(said) == 1 and "learning rate at its floor" in said[0] and "step 7" in said[0]
    pinned = {"health/std_mean": 0.0505, "health/saturated": 0.9}
    said = [w for _ in range(PATIENCE) for w in watch.check(pinned)]
    assert len(said) == 2 and "lower bound" in said[1] and "saturated" in said[0]
    assert len(watch.warnings) == 3


def test_a_run_records_health_figures_and_its_warnings(tmp_path):
    from devlearn.training import train

    cfg = tiny_run.config(tmp_path / "run", 64)
    result = train(cfg, tiny_run.registry(), infant_factory=tiny_run.factory, progress=False)
    row = result.last
    for key in (
        "learning_rate",
        "health/std_min",
        "health/std_mean",
        "health/std_max",
        "health/saturated",
        "health/explained_variance",
        "health/reward_scale",
        "loss/surrogate",
    ):
        assert key in row, key
    # the free head starts at 1.0 under a ceiling falling to 0.3 over the run: 64 steps of
    # 32 per iteration, the second iteration collected under the ceiling at half the run
    assert row["health/std_min"] == pytest.approx((1.0 * 0.3) ** 0.5, abs=0.02)
    assert result.warnings == []
    state = torch.load(tmp_path / "run" / "checkpoint_latest.pt", weights_only=False)
    assert set(state["reward_norm"]) == {
        "returns",
        "moments._mean",
        "moments._var",
        "moments._std",
        "moments.count",
    }
    paper = run_config(TinyBehavior, ["ppo.normalize_rewards=false"])
    assert paper.ppo.normalize_rewards is False


def test_the_end_of_run_summary_repeats_the_health_warnings(tmp_path):
    from devlearn.cli.summary import run_summary
    from devlearn.training.train import TrainResult

    warning = "learner warning at step 640: the surrogate loss has stayed >= 0 ..."
    result = TrainResult(tmp_path, 640, 20, {}, [warning])
    assert f"  {warning}" in run_summary(result, "tiny", "close", 640).splitlines()
    assert "learner warning" not in run_summary(
        TrainResult(tmp_path, 640, 20), "tiny", "close", 640
    )
