"""devlearn.gym's single env: the ids, one config path, a run's rewards and episodes, the
curriculum's clock, seeding, rendering (on the fake infant; the real ones: the plugins' tests).

This folder is not named ``gym``: with ``tests/`` on the path it would shadow the old ``gym``
package that Stable-Baselines3 probes for."""

from __future__ import annotations

import numpy as np
import pytest

import devlearn.gym
from devlearn.api.errors import UsageError
from devlearn.config.resolve import RunRequest, resolve_config
from devlearn.config.run_config import to_dict
from devlearn.env import BehaviorEnv
from devlearn.gym.env import DevlearnEnv
from devlearn.testing import registry_for
from devlearn.testing.fake_infant import TinyBehavior, fake_infant_factory

REGISTRY = registry_for(TinyBehavior)


def make(overrides=None, **kwargs) -> DevlearnEnv:
    return DevlearnEnv(
        "tiny", overrides, registry=REGISTRY, infant_factory=fake_infant_factory, **kwargs
    )


def test_every_installed_behaviour_has_an_id():
    assert devlearn.gym.env_id("hand_to_mouth") == "devlearn/HandToMouth-v0"
    assert devlearn.gym.IDS["devlearn/SelfTouch-v0"] == "self_touch"
    assert devlearn.gym.IDS["devlearn/HandRegard-v0"] == "hand_regard"
    assert devlearn.gym.register_behaviors(REGISTRY) == {"devlearn/Tiny-v0": "tiny"}
    import gymnasium

    spec = gymnasium.spec("devlearn/Tiny-v0")
    assert spec.kwargs == {"behavior": "tiny"}
    assert spec.vector_entry_point == devlearn.gym.VECTOR_ENTRY_POINT
    del gymnasium.registry["devlearn/Tiny-v0"]


def test_the_config_is_devlearn_runs():
    with make({"seed": 3, "env.action_repeat": 2, "behavior.target": 0.25}, preset="") as env:
        request = RunRequest("tiny", ["seed=3", "env.action_repeat=2", "behavior.target=0.25"])
        assert to_dict(env.setup.config) == to_dict(resolve_config(request, REGISTRY))
        assert env.env.action_repeat == 2 and env.setup.behavior.config.target == 0.25
    with pytest.raises(UsageError, match="env.action_repeat must be at least 1"):
        make({"env.action_repeat": 0})
    with pytest.raises(UsageError, match="unknown config key 'behavior.targt'.*behavior.target"):
        make(["behavior.targt=1"])
    with pytest.raises(UsageError, match="curiosity=rnd: learned rewards"):
        make(["curiosity=rnd"])


def test_rewards_observations_and_episodes_are_a_runs_env():
    env = make({"seed": 5, "env.action_repeat": 2})
    cfg = env.setup.config
    same = BehaviorEnv(TinyBehavior(cfg.behavior), 5, fake_infant_factory, action_repeat=2)
    rng = np.random.default_rng(0)
    try:
        obs, info = env.reset()
        assert info == {"stage": "fixed"}
        assert np.array_equal(obs["proprioception"], same.reset()["proprioception"])
        for t in range(7):  # 10 physics steps an episode: 5 decisions
            action = rng.uniform(-1, 1, 3).astype(np.float32)
            obs, reward, terminated, truncated, info = env.step(action)
            expected = same.step(action)
            assert reward == expected[1] and not terminated and truncated == (t == 4)
            terms = [info["reward/reach"], info["reward/counter"]]
            assert terms == pytest.approx([expected[1], 0.0]) and info["stage"] == "fixed"
            if t != 4:
                assert np.array_equal(obs["proprioception"], expected[0]["proprioception"])
                assert not any(key.startswith("episode/") for key in info)
                continue
            # the episode's last observation, then reset() gives the next one's first
            assert np.array_equal(obs["proprioception"], same.final_observation["proprioception"])
            assert not np.array_equal(obs["proprioception"], expected[0]["proprioception"])
            summary = expected[4]
            assert info["episode/reward/reach"] == summary["reward/reach"]
            assert info["episode/metrics/close"] == summary["metrics/close"]
            obs, _ = env.reset()
            assert np.array_equal(obs["proprioception"], expected[0]["proprioception"])
    finally:
        env.close()
        same.close()


def test_the_curriculum_advances_at_a_runs_iteration_boundaries():
    # stage 1 after 6 physics steps; a run looks at the count every 4 decisions (8 steps)
    settings = {"behavior.stage_steps": 6, "ppo.num_steps_per_env": 4, "env.action_repeat": 2}
    with make(settings) as env:
        env.reset()
        stages = [env.step(np.zeros(3))[4]["stage"] for _ in range(6)]
        assert stages == ["fixed"] * 4 + ["random"] * 2
        assert env.clock.physics_steps == 12 and env.env.stage == {"random_pose": True}


def test_seeds_repeat_and_differ():
    with make({"behavior.stage_steps": 0}) as env:  # random poses from the start
        first, _ = env.reset(seed=11)
        again, _ = env.reset(seed=11)
        other, _ = env.reset(seed=12)
        assert np.array_equal(first["proprioception"], again["proprioception"])
        assert not np.array_equal(first["proprioception"], other["proprioception"])
        with make({"behavior.stage_steps": 0, "seed": 11}) as seeded:  # the config's seed
            assert np.array_equal(seeded.reset()[0]["proprioception"], first["proprioception"])


def test_rgb_array_renders_the_eyes_and_the_view():
    # (check_env: devlearn.testing.check_gymnasium, tests/testing/test_conformance.py)
    with make(render_mode="rgb_array") as env:
        env.reset()
        frame = env.render()
        assert frame.shape == (256, 2 * 256 + 384, 3) and frame.dtype == np.uint8
        assert "eyes" in env.env.infant.senses  # added for the picture, not observed
        assert set(env.observation_space.spaces) == {"proprioception"}
    assert make().render() is None


def test_the_body_has_a_runs_age_at_every_iteration_boundary():
    """infant.age_months builds the body at that age; infant.growth changes it where a run
    would: at its iteration boundaries (ppo.num_steps_per_env decisions)."""
    with make({"infant.age_months": 6}) as fixed:
        assert fixed.env.age_months == 6 and fixed.env.infant.age_months == 6
    cfg = make().setup.config
    decisions = cfg.ppo.num_steps_per_env
    steps = decisions * cfg.env.action_repeat  # one env: physics steps of an iteration
    # 6 -> 18 months in three pieces of one iteration each: 6, 12, 18 months
    growing = make(
        {"infant.growth": "6->18", "infant.growth_every": steps, "total_steps": 3 * steps}
    )
    try:
        growing.reset(seed=0)
        ages = [growing.env.infant.age_months]
        for _ in range(2):
            for _ in range(decisions):
                growing.step(np.zeros(growing.action_space.shape, np.float32))
            ages.append(growing.env.infant.age_months)
        assert ages == [6.0, 12.0, 18.0]
    finally:
        growing.close()


def test_a_closed_env_says_so():
    # issue #55, fault 14: as its vector env (a step after close read freed state)
    from gymnasium.error import ClosedEnvironmentError

    env = make()
    env.reset()
    env.close()
    with pytest.raises(ClosedEnvironmentError, match=r"^step\(\) on a closed DevlearnEnv"):
        env.step(env.action_space.sample())
    with pytest.raises(UsageError, match="overrides must be a mapping .* got 5"):
        make(5)
