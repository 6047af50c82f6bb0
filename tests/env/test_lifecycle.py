"""Episode hooks: on_episode_start once per episode and before_step once per step, in order,
in one env, in an in-process batch and through worker processes."""

from __future__ import annotations

import functools

import numpy as np
import pytest
import torch

from devlearn.env import BehaviorEnv, DevVecEnv
from devlearn.testing.fake_infant import TinyConfig, fake_infant_factory
from devlearn.testing.hook_tracker import HookTracker

STEPS = 5
factory = functools.partial(fake_infant_factory, episode_steps=STEPS)


def expected(episode: int) -> dict[str, float]:
    return {
        "metrics/episode": float(episode),
        "metrics/starts": 1.0,
        "metrics/before_steps": float(STEPS),
        "metrics/facts": float(STEPS + 1),
        "metrics/ordered": 1.0,
        "metrics/problems": 0.0,
    }


def metrics(info: dict[str, float]) -> dict[str, float]:
    return {k: v for k, v in info.items() if k.startswith("metrics/")}


def test_hooks_in_one_env_over_several_episodes():
    behavior = HookTracker(TinyConfig())
    env = BehaviorEnv(behavior, seed=0, infant_factory=factory)
    env.reset()
    assert behavior.log.episodes == 1 and behavior.log.calls == ["start", "facts"]
    infos = []
    rng = np.random.default_rng(0)
    for _ in range(3 * STEPS):
        *_, info = env.step(rng.uniform(-3, 3, 3))  # out of range: hooks see it clipped
        if info is not None:
            infos.append(metrics(info))
    assert infos == [expected(1), expected(2), expected(3)]
    assert behavior.log.episodes == 4 and behavior.log.calls == ["start", "facts"]  # 4th just began


@pytest.mark.parametrize("workers", [0, 2])
def test_hooks_through_a_batch_and_worker_processes(workers):
    env = DevVecEnv(HookTracker(TinyConfig()), 4, seed=0, workers=workers, infant_factory=factory)
    try:
        ends = []
        for _ in range(3 * STEPS):
            *_, extras = env.step(torch.rand(4, 3) * 4 - 2)
            if extras["episode_infos"]:
                ends.append([metrics(info) for info in extras["episode_infos"]])
        assert ends == [[expected(k)] * 4 for k in (1, 2, 3)]  # all 4 envs end together
    finally:
        env.close()
