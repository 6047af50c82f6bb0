"""Facts and observations, one batched path: per_env, the batched step path and its guard."""

from __future__ import annotations

import functools

import numpy as np
import pytest

import devlearn
from devlearn.api.batching import EnvBatch
from devlearn.env.behavior_env import BehaviorEnv, step_batch
from devlearn.env.guards import GuardError
from devlearn.env.workers import make_envs, step_envs
from devlearn.testing.fake_infant import FakeInfant, TinyBehavior, TinyConfig, fake_infant_factory

factory = functools.partial(fake_infant_factory, episode_steps=5)


class BatchedTiny(TinyBehavior):
    """TinyBehavior with batched facts and observations (one call for all infants)."""

    calls: list[int] = []  # batch sizes of observe calls, shared by all copies
    nan_at: tuple[int, int] | None = None  # (row, infant step) that observes NaN

    def facts(self, batch):
        positions = np.array([infant.position for infant in batch.infants])
        return [{"position": row} for row in positions]

    def observe(self, batch, facts):
        BatchedTiny.calls.append(len(batch))
        obs = np.array([f["position"] for f in facts], dtype=np.float32)
        row, step = self.nan_at or (len(batch), 0)
        if row < len(batch) and batch.infants[row].steps_taken == step:
            obs[row, 1] = np.nan
        return {"proprioception": obs}


def test_per_env_methods_run_each_env_on_its_own_behaviour():
    behavior = TinyBehavior(TinyConfig(use_eyes=True))
    infants = [FakeInfant("crib") for _ in range(3)]
    for k, infant in enumerate(infants):
        infant.position = np.full(3, 0.5 * k)
    batch = EnvBatch(infants, [behavior] * 3)
    assert behavior.facts(batch) == [{}, {}, {}]  # the contract's default: no facts
    obs = behavior.observe(batch, behavior.facts(batch))
    assert obs["proprioception"].shape == (3, 3) and obs["eyes"].shape == (3, 2, 8, 8, 3)
    for k in range(len(infants)):
        single = behavior.observe(batch.one(k), [{}])
        for name in single:
            assert single[name].shape[0] == 1
            assert obs[name][k].tobytes() == single[name][0].tobytes()


def test_per_env_decorates_facts_or_observe_only():
    with pytest.raises(TypeError, match="facts or observe, not reward_terms"):

        @devlearn.per_env
        def reward_terms(self):
            return []


def test_batched_envs_step_like_per_env_envs_and_fill_the_batch_arrays():
    """A worker's batch (one observe per step, written at once into its rows of the
    arrays) gives the observations, rewards and episode ends of envs stepped one by one; the
    rows of envs that reset hold the next episode's first observation."""
    BatchedTiny.calls = []
    batch = make_envs(BatchedTiny(), [0, 1, 2], factory, offset=2)
    single = [BehaviorEnv(TinyBehavior(), s, factory) for s in range(3)]
    arrays = {
        "obs/proprioception": np.full((5, 3), -9.0, np.float32),
        "actions": np.zeros((5, 3), np.float32),
        "rewards": np.zeros(5, np.float32),
        "dones": np.zeros(5, bool),
        "time_outs": np.zeros(5, bool),
    }
    for env in batch + single:
        env.reset()
    rng = np.random.default_rng(0)
    ends = 0
    for _ in range(12):
        arrays["actions"][2:] = rng.uniform(-1.5, 1.5, (3, 3))
        infos = step_envs(batch, 2, arrays)
        for i, env in enumerate(single):
            obs, reward, done, _, info = env.step(arrays["actions"][2 + i])
            assert arrays["obs/proprioception"][2 + i].tobytes() == obs["proprioception"].tobytes()
            assert (arrays["rewards"][2 + i], arrays["dones"][2 + i]) == (np.float32(reward), done)
            assert ((2 + i, info) in infos) == done
            ends += done
    assert ends == 6 and BatchedTiny.calls.count(3) == 12  # one a step; resets: batches of one
    assert set(BatchedTiny.calls) == {1, 3}
    assert np.all(arrays["obs/proprioception"][:2] == -9.0)  # other workers' rows untouched


def test_per_env_facts_use_each_env_own_instance():
    """Facts written per env: every env calls its own behaviour (it may keep per-env state)."""

    class Stateful(TinyBehavior):
        @devlearn.per_env
        def facts(self, infant):
            self.seen = getattr(self, "seen", 0) + 1
            return {"seen": self.seen}

    envs = make_envs(Stateful(), [0, 1], factory)
    for env in envs:
        env.reset()
    for _ in range(3):
        step_batch(envs, np.zeros((2, 3)))
    assert [env.behavior.seen for env in envs] == [4, 4]  # a reset and three steps each


def test_guard_names_the_env_and_step_of_a_bad_batched_observation():
    BatchedTiny.nan_at = (1, 3)
    try:
        envs = make_envs(BatchedTiny(), [0, 1, 2], factory, offset=4)
        for env in envs:
            env.reset()
        step_batch(envs, np.zeros((3, 3)))
        step_batch(envs, np.zeros((3, 3)))
        with pytest.raises(GuardError) as caught:
            step_batch(envs, np.zeros((3, 3)))
    finally:
        BatchedTiny.nan_at = None
    error = caught.value
    assert (error.kind, error.name, error.env_index, error.step) == (
        "observation",
        "proprioception",
        5,
        3,
    )
