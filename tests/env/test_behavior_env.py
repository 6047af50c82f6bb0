"""BehaviorEnv: episodes, time-outs, per-term sums, stages, seeding and resumable state."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest

import devlearn
from devlearn.env import BehaviorEnv
from devlearn.testing.fake_infant import TinyBehavior, TinyConfig, fake_infant_factory

factory = functools.partial(fake_infant_factory, episode_steps=5)


def make_env(seed: int = 0, **config) -> BehaviorEnv:
    return BehaviorEnv(TinyBehavior(TinyConfig(**config)), seed, infant_factory=factory)


def test_episode_times_out_and_reports_term_sums():
    env = make_env(target=0.45)
    obs = env.reset()
    np.testing.assert_array_equal(obs["proprioception"], np.zeros(3))
    rewards = []
    for t in range(5):
        obs, reward, done, time_out, info = env.step(np.ones(3))
        rewards.append(reward)
        assert (done, time_out) == ((t == 4), (t == 4))
        assert (info is None) == (t < 4)
    # positions 0.1..0.5 -> reach = -|position - 0.45|
    np.testing.assert_allclose(rewards, [-0.35, -0.25, -0.15, -0.05, -0.05], atol=1e-6)
    assert set(info) == {"reward/reach", "reward/counter", "metrics/close"}
    assert info["reward/reach"] == sum(rewards)
    assert info["reward/counter"] == 0.0  # weight 0: logged weighted
    assert info["metrics/close"] == 0.6  # 0.3, 0.4 and 0.5 are within 0.2 of 0.45
    # auto-reset: the returned observation is the new episode's first one
    np.testing.assert_array_equal(obs["proprioception"], np.zeros(3))
    assert env.episode_step == 0


def test_actions_are_clipped():
    env = make_env()
    env.reset()
    obs, *_ = env.step(np.full(3, 50.0))
    np.testing.assert_allclose(obs["proprioception"], np.full(3, 0.1), atol=1e-6)


def test_random_pose_stage_and_seeding():
    a, b, c = make_env(seed=1), make_env(seed=1), make_env(seed=2)
    for env in (a, b, c):
        env.set_stage({"random_pose": True})
    pa, pb, pc = (env.reset()["proprioception"] for env in (a, b, c))
    assert np.any(pa != 0)
    np.testing.assert_array_equal(pa, pb)
    assert not np.array_equal(pa, pc)


def test_state_dict_restores_terms_rng_and_stage():
    env = make_env(seed=3)
    env.set_stage({"random_pose": True})
    env.reset()
    for _ in range(7):
        env.step(np.zeros(3))
    state = env.state_dict()
    expected_next = env.reset()["proprioception"]

    fresh = make_env(seed=99)
    fresh.load_state_dict(state)
    assert fresh.terms[1].terms[0].count == 7  # a per-env term, wrapped (BatchedFromPerEnv)
    assert fresh.stage == {"random_pose": True}
    np.testing.assert_array_equal(fresh.reset()["proprioception"], expected_next)


def test_batch_context_stacks_facts_of_any_kind():
    from devlearn import BatchContext, StepContext

    def ctx(value):
        return StepContext(None, {}, {"f": value}, 0, False)

    one = BatchContext([ctx([True, False])])
    assert one.stack("f", bool).shape == (1, 2) and one.stack("f", bool).dtype == bool
    many = BatchContext([ctx(np.array([1, 0])), ctx([0, 1]), ctx((1, 1))])
    np.testing.assert_array_equal(many.stack("f", bool), [[1, 0], [0, 1], [1, 1]])
    assert many.stack("f", bool) is many.stack("f", bool)  # computed once per step


def test_batched_term_of_the_wrong_shape_is_named():
    import pytest

    import devlearn
    from devlearn.env.behavior_env import share_batched_terms, term_values

    class Wrong(devlearn.BatchedIntrinsicReward):
        """Returns one value too many."""

        name = "wrong"

        def __call__(self, batch):
            return np.zeros(len(batch) + 1)

    class WithWrong(TinyBehavior):
        def reward_terms(self):
            return [Wrong()]

    envs = [BehaviorEnv(WithWrong(TinyConfig()), s, infant_factory=factory) for s in (0, 1)]
    share_batched_terms(envs)
    contexts = [env.advance(np.zeros(3)) for env in envs if env.reset() is not None]
    with pytest.raises(ValueError, match="'wrong' returned shape \\(3,\\); expected \\(2,\\)"):
        term_values(envs, contexts)


# --- the decision rate (env.action_repeat, issue #28) -----------------------------------


def test_a_decision_is_the_same_action_held_for_k_physics_steps_with_rewards_summed():
    held = BehaviorEnv(TinyBehavior(TinyConfig(target=0.45)), 0, factory, action_repeat=5)
    plain = make_env(target=0.45)
    held.reset(), plain.reset()
    rng = np.random.default_rng(0)
    for _ in range(3):  # three episodes of 5 physics steps: one decision each
        action = rng.uniform(-1, 1, 3)
        want_reward = 0.0
        for _ in range(5):
            want_obs, reward, want_done, _, want_info = plain.step(action)
            want_reward += reward
        obs, reward, done, time_out, info = held.step(action)
        np.testing.assert_array_equal(obs["proprioception"], want_obs["proprioception"])
        assert reward == want_reward and (done, time_out) == (want_done, True) and done
        assert info == want_info  # per-term sums and the evaluator saw every physics step
    assert held.infant.steps_taken == plain.infant.steps_taken == 15


def test_a_decision_rate_must_divide_the_episode():
    with pytest.raises(ValueError, match=r"action_repeat=3 must divide the episode \(5 physics steps\)"):
        BehaviorEnv(TinyBehavior(TinyConfig()), 0, factory, action_repeat=3)


class RenderedTiny(TinyBehavior):
    """Facts once per decision (as behaviours whose facts need renders); counts them."""

    facts_calls = 0

    def episode(self):
        return dataclasses.replace(super().episode(), facts_every_physics_step=False)

    @devlearn.per_env
    def facts(self, infant):
        type(self).facts_calls += 1
        return {}


def test_facts_once_per_decision_pay_the_reward_for_every_physics_step():
    ten = functools.partial(fake_infant_factory, episode_steps=10)
    env = BehaviorEnv(RenderedTiny(TinyConfig(target=0.45)), 0, ten, action_repeat=5)
    env.reset()
    RenderedTiny.facts_calls = 0
    _, reward, done, _, _ = env.step(np.ones(3))
    # physics ran 5 times; facts, rewards and the evaluator once, on the state reached
    assert env.infant.steps_taken == 5 and RenderedTiny.facts_calls == 1 and not done
    np.testing.assert_allclose(reward, 5 * -0.05, atol=1e-6)  # -|0.5 - 0.45|, held 5 steps
    _, reward, done, time_out, info = env.step(np.zeros(3))
    assert done and time_out and env.infant.steps_taken == 10  # the episode: 10 physics steps
    assert info["reward/reach"] == pytest.approx(2 * 5 * -0.05)
    assert info["metrics/close"] == 1.0  # two records, one per decision


class ObserveCounted(TinyBehavior):
    """Counts its observe() calls; ``readers`` picks whether a reward term reads observations
    (Reach) and whether the evaluator does (CloseEvaluator)."""

    observe_calls = 0
    readers = False

    @devlearn.per_env
    def observe(self, infant, facts):
        type(self).observe_calls += 1
        return {"proprioception": infant.proprioception()}

    def reward_terms(self):
        from devlearn.testing.fake_infant import Reach, StepCounter

        return [Reach(0.45)] if self.readers else [StepCounter()]

    def evaluation(self):
        if self.readers:
            return super().evaluation()
        return devlearn.EvalProtocol(evaluator=lambda training: devlearn.Evaluator())


@pytest.mark.parametrize("readers", [False, True])
def test_a_decision_observes_its_last_physics_step_unless_a_term_reads_the_others(readers):
    """Issue #54 item 5: inside a decision of 5 physics steps the policy sees only the last
    step's observations; the others are computed only when a reward term or the evaluator
    reads them (and then equal an env stepped every physics step: the test above)."""
    ObserveCounted.readers = readers
    ten = functools.partial(fake_infant_factory, episode_steps=10)
    env = BehaviorEnv(ObserveCounted(TinyConfig()), 0, ten, action_repeat=5)
    env.reset()
    ObserveCounted.observe_calls = 0
    obs, _, done, _, _ = env.step(np.ones(3))
    assert env.infant.steps_taken == 5 and not done
    assert ObserveCounted.observe_calls == (5 if readers else 1)
    assert isinstance(obs, dict)  # what the policy gets is a plain dict, as before
    np.testing.assert_array_equal(obs["proprioception"], env.infant.proprioception())
