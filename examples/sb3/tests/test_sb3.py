"""The Stable-Baselines3 example: SB3's VecEnv over devlearn's vector env, and PPO and SAC
trained on self-touch with a tiny budget, then evaluated by devlearn eval."""

from __future__ import annotations

import json
import pickle
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import train  # noqa: E402
from sb3_vec_env import GymnasiumVecEnv  # noqa: E402

from devlearn.gym.vector import DevlearnVectorEnv  # noqa: E402
from devlearn.testing import (  # noqa: E402
    PluginRegistry,
    TinyBehavior,
    fake_infant_factory,
    open_scripted_policy,
    registry_for,
    run_command,
    run_config,
)


def test_sb3_sees_the_final_observation_and_the_next_episode():
    envs = DevlearnVectorEnv(
        "tiny",
        2,
        overrides={"env.action_repeat": 2, "behavior.stage_steps": 0},
        registry=registry_for(TinyBehavior),
        infant_factory=fake_infant_factory,
    )
    venv = GymnasiumVecEnv(envs)
    try:
        venv.seed(3)
        obs = venv.reset()
        seeded, _ = DevlearnVectorEnv(
            "tiny",
            2,
            overrides={"behavior.stage_steps": 0},
            registry=registry_for(TinyBehavior),
            infant_factory=fake_infant_factory,
        ).reset(seed=3)
        assert np.array_equal(obs["proprioception"], seeded["proprioception"])  # seed + i
        actions = np.full((2, 3), 0.5, np.float32)
        for t in range(5):  # 10 physics steps an episode, 2 a decision
            last = obs["proprioception"]
            obs, rewards, dones, infos = venv.step(actions)
            assert rewards.shape == (2,) and "reward/reach" in infos[0]
            assert dones.tolist() == [t == 4] * 2
        for i in range(2):
            final = infos[i]["terminal_observation"]["proprioception"]
            assert np.allclose(final, np.clip(last[i] + 0.1, -2, 2), atol=1e-6)
            assert not np.allclose(obs["proprioception"][i], final)  # the next episode's first
            assert infos[i]["TimeLimit.truncated"] is True
            assert "episode/metrics/close" in infos[i] and "final_obs" not in infos[i]
    finally:
        venv.close()


@pytest.mark.slow
@pytest.mark.parametrize("algo", ["ppo", "sac"])
def test_sb3_trains_self_touch_and_devlearn_eval_scores_it(algo, tmp_path):
    out = tmp_path / algo
    tiny = ["--envs", "2", "--workers", "0", "--net", "32", "--threads", "1", "--seed", "2"]
    record = train.main(["--algo", algo, "--steps", "2000", "--out", str(out), *tiny])
    # devlearn's count: physics steps summed over the envs (PPO completes its last rollout)
    assert record["env_steps"] == 5 * record["decisions"] >= 2000
    assert record["stopped_by"] == "steps" and record["learner"] == f"sb3_{algo}"
    assert json.loads((out / "train.json").read_text())["seed"] == 2
    assert 0 < record["collect_s"] < record["learn_s"]  # the rollouts' share of learn()
    # the scripted policy acts as SB3's own deterministic prediction does
    with open(out / "vecnormalize.pkl", "rb") as f:
        normalizer = pickle.load(f)
    model = train.ALGORITHMS[algo].load(out / "model.zip", device="cpu")
    scripted = open_scripted_policy(out / "policy.pt", PluginRegistry(), "self_touch")
    rng = np.random.default_rng(0)
    for _ in range(3):
        obs = {
            "body_map": (rng.random(68) < 0.2).astype(np.float32),
            "proprioception": rng.normal(0, 2, 180).astype(np.float32),
        }
        expected, _ = model.predict(normalizer.normalize_obs(obs), deterministic=True)
        assert scripted.act(obs) == pytest.approx(expected, abs=1e-5)
    args = ["eval", "self_touch", "--checkpoint", str(out), "--episodes", "1", "--json"]
    done = run_command(*args, "--out", str(tmp_path / "eval"))
    assert done.code == 0, done.err
    summary = json.loads(done.out)
    assert summary["learner"] == f"sb3_{algo}" and summary["training_seed"] == 2
    assert summary["checkpoint_env_steps"] == record["env_steps"]
    assert summary["checkpoint"] == str(out / "policy.pt")
    assert summary["protocol"]["start"] == "random" and summary["protocol"]["action_repeat"] == 5
    assert 0.0 <= summary["score"] <= 1.0


def test_a_linear_schedule_reaches_sb3_as_its_linear_rate_and_fixed_stays_constant():
    ppo = {
        "num_steps_per_env": 8,
        "num_mini_batches": 2,
        "num_learning_epochs": 1,
        "gamma": 0.99,
        "lam": 0.95,
        "clip_param": 0.2,
        "entropy_coef": 0.0,
        "value_loss_coef": 1.0,
        "max_grad_norm": 1.0,
        "learning_rate": 0.002,
    }
    overrides = [f"ppo.{key}={value}" for key, value in ppo.items()]
    cfg = run_config(TinyBehavior, overrides, total_steps=1000, num_envs=2, workers=0)
    cfg.ppo.schedule, cfg.ppo.decay_share = "linear", 1.0
    rate = train.ppo_settings(cfg, [8])["learning_rate"]
    assert callable(rate) and rate(1.0) == 0.002 and rate(0.25) == pytest.approx(0.0005)
    assert pickle.loads(pickle.dumps(rate))(0.5) == pytest.approx(0.001)  # model.zip keeps it
    assert json.loads(json.dumps({"lr": rate}, default=repr)) == {"lr": "linear(0.002 -> 0)"}
    cfg.ppo.decay_share = 0.2  # held, then falling over the last 20% of the run
    rate = train.ppo_settings(cfg, [8])["learning_rate"]
    assert rate(0.5) == 0.002 and rate(0.1) == pytest.approx(0.001) and rate(0.0) == 0.0
    assert repr(rate) == "linear(0.002 -> 0 over the last 0.2)"
    for schedule in ("fixed", "adaptive"):
        cfg.ppo.schedule = schedule
        assert train.ppo_settings(cfg, [8])["learning_rate"] == 0.002
    # a run longer than ppo.full_rate_steps: devlearn's smaller step size, for every schedule
    cfg.total_steps = 2 * cfg.ppo.full_rate_steps
    assert train.ppo_settings(cfg, [8])["learning_rate"] == 0.001
    cfg.ppo.schedule = "linear"
    assert train.ppo_settings(cfg, [8])["learning_rate"](1.0) == 0.001
