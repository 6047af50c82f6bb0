"""EnvSettings: the run's settled env settings, one frozen object from DevVecEnv down to every
BehaviorEnv, in process and in worker processes."""

from __future__ import annotations

import dataclasses
import functools

import pytest
import torch

from devlearn.env import BehaviorEnv, DevVecEnv, EnvSettings
from devlearn.env.workers import make_envs
from devlearn.testing.fake_infant import TinyBehavior, TinyConfig, fake_infant_factory

factory = functools.partial(fake_infant_factory, episode_steps=10)


def test_settings_are_one_frozen_object_that_every_env_holds():
    settings = EnvSettings(action_repeat=5)
    envs = make_envs(TinyBehavior(TinyConfig()), [0, 1, 2], factory, settings=settings)
    assert all(env.settings is settings and env.action_repeat == 5 for env in envs)
    with pytest.raises(dataclasses.FrozenInstanceError):
        settings.action_repeat = 2  # type: ignore[misc]
    with pytest.raises(TypeError, match="action_repeat must be an int, got 2.5"):
        EnvSettings(action_repeat=2.5)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="settings or action_repeat, not both"):
        BehaviorEnv(TinyBehavior(TinyConfig()), 0, factory, action_repeat=5, settings=settings)
    assert BehaviorEnv(TinyBehavior(TinyConfig()), 0, factory).settings == EnvSettings()


@pytest.mark.parametrize("workers", [0, 1])
def test_the_envs_step_at_the_rate_the_settings_give(workers):
    # An episode of 10 physics steps is 2 decisions of 5: it ends on the second step, in a
    # worker process as in process (the settings travel down to the worker's envs).
    vec = DevVecEnv(
        TinyBehavior(TinyConfig(use_eyes=False)),
        2,
        seed=0,
        workers=workers,
        infant_factory=factory,
        settings=EnvSettings(action_repeat=5),
    )
    try:
        assert vec.settings == EnvSettings(action_repeat=5)
        dones = [bool(vec.step(torch.zeros(2, vec.num_actions))[2].all()) for _ in range(4)]
        assert dones == [False, True, False, True]
    finally:
        vec.close()
