"""Envs whose body grows (issue #41): rebuilt at a new age in process and in workers, the
episode carried on."""

from __future__ import annotations

import functools

import numpy as np
import pytest
import torch
from tiny_behaviors import AgeBehavior

from devlearn.env import DevVecEnv
from devlearn.env.behavior_env import BehaviorEnv
from devlearn.testing.fake_infant import fake_infant_factory

factory = functools.partial(fake_infant_factory, episode_steps=5)


def test_an_env_rebuilt_at_a_new_age_carries_its_episode_on():
    env = BehaviorEnv(AgeBehavior(), 0, factory, age_months=6.0)
    env.reset()
    assert env.infant.age_months == 6.0
    env.step(np.ones(3))
    old = env.infant
    position, step = old.position.copy(), env.episode_step
    env.set_age(9.5)
    assert env.infant is not old and env.infant.age_months == 9.5 and env.age_months == 9.5
    np.testing.assert_array_equal(env.infant.position, position)  # the same pose...
    assert env.episode_step == step and env.infant.steps_taken == old.steps_taken  # ...episode
    _, reward, *_ = env.step(np.ones(3))
    assert reward == 9.5  # the new body took the step
    same = env.infant
    env.set_age(9.5)
    assert env.infant is same  # no rebuild without a change


@pytest.mark.parametrize("workers", [0, 2])
def test_set_age_reaches_every_env(workers):
    env = DevVecEnv(AgeBehavior(), 4, 0, workers, infant_factory=factory, age_months=None)
    try:
        _, rewards, _, _ = env.step(torch.zeros(4, 3))
        assert rewards.tolist() == [-1.0] * 4  # the default body
        env.set_age(12.0)
        assert env.age_months == 12.0
        for _ in range(7):  # across an episode's end: the reset body keeps its age
            _, rewards, _, _ = env.step(torch.zeros(4, 3))
            assert rewards.tolist() == [12.0] * 4
        env.set_age(None)
        _, rewards, _, _ = env.step(torch.zeros(4, 3))
        assert rewards.tolist() == [-1.0] * 4
    finally:
        env.close()


def test_envs_built_at_an_age():
    env = DevVecEnv(AgeBehavior(), 2, 0, 1, infant_factory=factory, age_months=3.0)
    try:
        _, rewards, _, _ = env.step(torch.zeros(2, 3))
        assert rewards.tolist() == [3.0, 3.0]
    finally:
        env.close()
