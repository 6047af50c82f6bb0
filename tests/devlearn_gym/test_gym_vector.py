"""devlearn.gym's vector env: a run's batch (DevVecEnv) behind Gymnasium's vector API, with
same-step autoreset, seeding, the run memory merged at a run's iteration boundaries, workers."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import torch
from gymnasium.vector import AutoresetMode

from devlearn.env import DevVecEnv
from devlearn.gym.vector import DevlearnVectorEnv
from devlearn.testing import registry_for
from devlearn.testing.fake_infant import TinyBehavior, fake_infant_factory

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "env"))
from tiny_behaviors import NoveltyBehavior  # noqa: E402

REGISTRY = registry_for(TinyBehavior, NoveltyBehavior)


def make(num_envs=3, workers=0, overrides=None, behavior="tiny") -> DevlearnVectorEnv:
    return DevlearnVectorEnv(
        behavior,
        num_envs,
        workers,
        overrides,
        registry=REGISTRY,
        infant_factory=fake_infant_factory,
    )


def rollout(envs, decisions: int, seed: int = 0) -> list:
    rng = np.random.default_rng(seed)
    steps = [envs.reset()]
    for _ in range(decisions):
        steps.append(envs.step(rng.uniform(-1, 1, (envs.num_envs, 3)).astype(np.float32)))
    return steps


def test_same_step_autoreset_returns_the_next_episode_and_the_final_observations():
    envs = make(overrides={"behavior.stage_steps": 0, "env.action_repeat": 2})
    rng = np.random.default_rng(1)
    try:
        assert envs.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
        assert envs.observation_space["proprioception"].shape == (3, 3)
        last, info = envs.reset()
        assert list(info["stage"]) == ["random"] * 3
        for t in range(6):  # 10 physics steps, 2 a decision: the episode ends at t == 4
            actions = rng.uniform(-1, 1, (3, 3)).astype(np.float32)
            obs, rewards, terminated, truncated, info = envs.step(actions)
            assert rewards.dtype == np.float32 and not terminated.any()
            assert truncated.tolist() == [t == 4] * 3
            assert info["reward/reach"].shape == (3,) and info["_reward/reach"].all()
            # the fake infant moves 0.1 * action a physics step
            moved = last["proprioception"] + 0.2 * actions
            if t != 4:
                assert "final_obs" not in info and "final_info" not in info
                assert np.allclose(obs["proprioception"], moved, atol=1e-6)
            else:
                assert info["_final_obs"].all() and info["_final_info"].all()
                final = np.stack([f["proprioception"] for f in info["final_obs"]])
                assert np.allclose(final, moved, atol=1e-6)
                assert not np.allclose(obs["proprioception"], moved, atol=0.01)  # new episodes
                assert info["final_info"]["episode/metrics/close"].shape == (3,)
                assert info["final_info"]["_episode/reward/reach"].all()
            last = obs
    finally:
        envs.close()


def test_rewards_are_the_runs_batch_rewards():
    envs = make(overrides={"env.action_repeat": 1})
    batch = DevVecEnv(TinyBehavior(), 3, 0, 0, infant_factory=fake_infant_factory)
    rng = np.random.default_rng(2)
    try:
        envs.reset()
        for _ in range(12):
            actions = rng.uniform(-1, 1, (3, 3)).astype(np.float32)
            obs, rewards, _, truncated, info = envs.step(actions)
            theirs, their_rewards, dones, _ = batch.step(torch.from_numpy(actions))
            assert rewards.tobytes() == their_rewards.numpy().tobytes()
            assert obs["proprioception"].tobytes() == theirs["proprioception"].numpy().tobytes()
            assert truncated.tolist() == dones.bool().tolist()
            terms = info["reward/reach"] + info["reward/counter"]
            assert terms == pytest.approx(rewards, abs=1e-6)
    finally:
        envs.close()
        batch.close()


def test_reset_seeds_env_i_with_seed_plus_i():
    envs = make(overrides={"behavior.stage_steps": 0})
    try:
        first, _ = envs.reset(seed=7)
        rollout(envs, 3)
        again, _ = envs.reset(seed=7)
        assert np.array_equal(first["proprioception"], again["proprioception"])
        assert len({row.tobytes() for row in first["proprioception"]}) == 3
        seeded = make(overrides={"behavior.stage_steps": 0, "seed": 7})  # built with seed 7
        try:
            assert np.array_equal(seeded.reset()[0]["proprioception"], first["proprioception"])
        finally:
            seeded.close()
    finally:
        envs.close()


def test_workers_give_what_one_process_gives_and_close():
    settings = {"behavior.stage_steps": 0, "env.action_repeat": 2}
    local, pooled = make(overrides=settings), make(workers=2, overrides=settings)
    try:
        for mine, theirs in zip(rollout(local, 7), rollout(pooled, 7)):
            obs, *rest, info = mine
            their_obs, *their_rest, their_info = theirs
            assert obs["proprioception"].tobytes() == their_obs["proprioception"].tobytes()
            for a, b in zip(rest, their_rest):
                assert np.array_equal(a, b)
            if "final_obs" in info:
                for a, b in zip(info["final_obs"], their_info["final_obs"]):
                    assert a["proprioception"].tobytes() == b["proprioception"].tobytes()
        procs = list(pooled.envs._pool.procs)
    finally:
        local.close()
        pooled.close()
    assert procs and not any(p.is_alive() for p in procs)


def test_workers_merge_their_run_memory_at_a_runs_iteration_boundary():
    # 3 envs on 2 workers: batches of 2 and 1; a run merges every ppo.num_steps_per_env
    envs = make(3, 2, {"ppo.num_steps_per_env": 4, "env.action_repeat": 1}, "novelty")

    def widest() -> list[int]:
        states = envs.envs.state_dict()["envs"]
        return [int(s["terms"]["step_novelty"]["widest"][0]) for s in states]

    try:
        envs.reset()
        for _ in range(3):
            envs.step(np.zeros((3, 3), np.float32))
        assert widest() == [2, 2, 1]  # each worker its own memory
        envs.step(np.zeros((3, 3), np.float32))
        assert widest() == [2, 2, 2]  # merged at the boundary, as a run merges them
    finally:
        envs.close()


def test_make_vec_builds_devlearns_vector_env_for_an_installed_behaviour():
    import gymnasium

    import devlearn.gym

    envs = devlearn.gym.make_vec("devlearn/SelfTouch-v0", 2, overrides={"seed": 1})
    try:
        assert isinstance(envs, DevlearnVectorEnv) and envs.spec.id == "devlearn/SelfTouch-v0"
        assert envs.setup.config.seed == 1 and envs.setup.config.num_envs == 2
        assert set(envs.single_observation_space.spaces) == {"body_map", "proprioception"}
        obs, _ = envs.reset()
        obs, rewards, _, _, info = envs.step(envs.action_space.sample())
        assert obs["proprioception"].shape == (2, 180) and rewards.shape == (2,)
        assert "reward/touch_novelty" in info
    finally:
        envs.close()
    plain = gymnasium.make_vec("devlearn/SelfTouch-v0", num_envs=2)  # its vector entry point
    try:
        assert isinstance(plain, DevlearnVectorEnv)
    finally:
        plain.close()


@pytest.mark.parametrize("workers", [0, 2])
def test_the_body_has_a_runs_age_at_every_iteration_boundary(workers):
    """infant.age_months builds the body at that age; infant.growth changes it at a run's
    iteration boundaries, to the schedule's age at the run's step count (issue #41); the
    rebuild inside workers is tests/env/test_growth_env.py's."""
    fixed = make(2, workers, {"infant.age_months": 6})
    try:
        assert fixed.envs.age_months == 6
        cfg = fixed.setup.config
    finally:
        fixed.close()
    decisions = cfg.ppo.num_steps_per_env
    steps = 2 * decisions * cfg.env.action_repeat  # two envs: physics steps of an iteration
    # 6 -> 18 months in three pieces of one iteration each: 6, 12, 18 months
    overrides = {"infant.growth": "6->18", "infant.growth_every": steps, "total_steps": 3 * steps}
    growing = make(2, workers, overrides)
    try:
        growing.reset(seed=0)
        ages = [growing.envs.age_months]
        for _ in range(2):
            for _ in range(decisions):
                growing.step(np.zeros((2, growing.single_action_space.shape[0]), np.float32))
            ages.append(growing.envs.age_months)
        assert ages == [6.0, 12.0, 18.0]
    finally:
        growing.close()


@pytest.mark.parametrize("workers", [0, 1])
def test_a_closed_vector_env_says_so(workers):
    # issue #55, fault 14: a step after close() read the freed buffers: KeyError 'actions'
    from gymnasium.error import ClosedEnvironmentError

    envs = make(num_envs=2, workers=workers)
    envs.reset()
    envs.close()
    actions = np.zeros((2, envs.single_action_space.shape[0]), np.float32)
    with pytest.raises(ClosedEnvironmentError, match=r"^step\(\) on a closed DevlearnVectorEnv"):
        envs.step(actions)
    with pytest.raises(ClosedEnvironmentError, match=r"^reset\(\) on a closed DevlearnVectorEnv"):
        envs.reset()
    envs.close()  # still safe twice


def test_overrides_of_another_kind_say_what_is_valid():
    # issue #55, fault 14: gym.make(..., overrides=5) was a raw TypeError
    from devlearn.api.errors import UsageError

    for bad in (5, "seed=3", [3], {"seed"}):
        with pytest.raises(UsageError, match=r"^overrides must be a mapping of config keys to"):
            make(overrides=bad)
