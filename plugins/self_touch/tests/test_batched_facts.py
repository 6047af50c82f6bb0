"""A batch's self_touch facts and observations (one compiled pass) are each environment's alone
(the numpy reference), bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from devlearn_self_touch import SelfTouch, SelfTouchConfig
from devlearn_self_touch.behavior import touch_facts, touch_observations
from per_env_rewards import per_env_reward_terms
from self_touch_fakes import FakeInfant, ScriptedInfant, same_info

import devlearn
from devlearn import EnvBatch, build_infant
from devlearn.testing import (
    ConformanceError,
    Play,
    check_batched_observations,
    facts_of,
    place_hand_on_body,
)

SOURCES = ("hands", "threshold", "hands_or_threshold")


class PerEnvSelfTouch(SelfTouch):
    """SelfTouch on the per-environment path: the numpy facts and observations, terms per env."""

    @devlearn.per_env
    def facts(self, infant):
        return touch_facts(infant, self.config.touch_source, self.config.touch_threshold)

    @devlearn.per_env
    def observe(self, infant, facts):
        return touch_observations(infant, facts, self.config.body_map_scale)

    def reward_terms(self):
        return per_env_reward_terms(self.config)


@pytest.fixture(scope="module")
def cribs():
    infants = [build_infant("crib", senses=SelfTouch().episode().senses) for _ in range(3)]
    yield infants
    for infant in infants:
        infant.close()


def test_recorded_crib_steps_give_the_same_facts_and_observations(cribs):
    """Three real infants in one batch, random poses and actions, a hand placed on the body
    now and then: every step, every touch source, the batch equals each environment alone."""
    behaviors = [SelfTouch(SelfTouchConfig(touch_source=s)) for s in SOURCES]
    rng = np.random.default_rng(11)
    hand_steps = threshold_steps = 0
    for step in range(240):
        for infant in cribs:
            if step % 80 == 0:
                infant.reset(rng, random_pose=True)
            if step % 20 == 10:
                place_hand_on_body(infant, rng)
            infant.step(rng.uniform(-1, 1, infant.action_dim))
        for behavior in behaviors:
            check_batched_observations(behavior, cribs, f"at step {step}")
        facts = behaviors[1].facts(EnvBatch(cribs, behaviors[1:2] * len(cribs)))
        hand_steps += any(f["hand_contacts"].any() for f in facts)
        threshold_steps += any(f["touched"].any() for f in facts)
    assert hand_steps > 10 and threshold_steps > 100  # both kinds of touch were compared


def test_threshold_is_compared_in_float32_as_facts_does():
    """g_j exactly float32(0.1): facts() compares the float32 map with the Python float in
    float32 (not touched); a float64 comparison would call it touched."""
    touch = np.zeros((204, 3), np.float32)
    touch[0] = (np.float32(0.3), 0, 0)  # region 0 holds 3 sensors: g_0 = 0.3 / 3
    touch[6:9] = np.float32(1e5)  # a kick into the mattress: large forces
    infant = FakeInfant(touch)
    behavior = SelfTouch(SelfTouchConfig(touch_source="threshold", touch_threshold=0.1))
    facts = facts_of(behavior, infant)
    assert facts["body_map"][0] == np.float32(0.1) and float(facts["body_map"][0]) > 0.1
    assert not facts["touched"][0] and facts["touched"][2]
    check_batched_observations(behavior, [infant, FakeInfant(), infant])


def test_the_check_names_a_batched_fact_that_differs():
    class Wrong(SelfTouch):
        def facts(self, batch):
            facts = super().facts(batch)
            if len(batch) > 1:  # a batch, not an environment alone
                facts[-1]["touched"] = ~facts[-1]["touched"]
            return facts

    with pytest.raises(ConformanceError, match=r"facts\(\)\[1\]\['touched'\] of a batch differs"):
        check_batched_observations(Wrong(), [FakeInfant(), FakeInfant()])


def test_a_worker_batch_calls_facts_once_per_step():
    calls = []

    class Counting(SelfTouch):
        def facts(self, batch):
            calls.append(len(batch))
            return super().facts(batch)

    envs = Play(Counting(), 3, infant_factory=ScriptedInfant)
    envs.reset()
    envs.play(5)
    assert calls == [1, 1, 1] + [3] * 5  # the resets alone, then one call a step


def test_real_rollout_is_the_same_on_the_batched_and_per_env_paths():
    """Observations, rewards, dones and episode summaries of a worker's three envs (batched
    facts, observations and terms) against three envs on the per-environment path."""
    config = SelfTouchConfig(lifetime_memory="per_env")  # the reference terms are per env
    batch = Play(SelfTouch(config), 3)
    reference = [Play(PerEnvSelfTouch(config), seed=seed) for seed in range(3)]
    rng = np.random.default_rng(2)
    try:
        for env in [batch, *reference]:
            env.set_stage({"random_pose": True})
            env.episode_steps = 60
        for a, b in zip(batch.reset(), reference):
            assert _same_obs(a, b.reset()[0])
        paid = 0.0
        for step in range(150):
            if step % 15 == 5:
                for a, b in zip(batch.infants, reference):
                    state = rng.bit_generator.state
                    place_hand_on_body(a, rng)
                    rng.bit_generator.state = state  # the same placement for both
                    place_hand_on_body(b.infants[0], rng)
            actions = rng.uniform(-1, 1, (3, batch.action_dim))
            got = batch.step(actions)
            want = [env.step(action)[0] for env, action in zip(reference, actions)]
            for (o1, r1, d1, t1, i1), (o2, r2, d2, t2, i2) in zip(got, want):
                assert _same_obs(o1, o2), step
                assert (r1, d1, t1) == (r2, d2, t2) and same_info(i1, i2), step
                paid += r1
        assert paid > 0  # touches were paid for
    finally:
        for env in [batch, *reference]:
            env.close()


def _same_obs(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(
        a[k].dtype == b[k].dtype and a[k].tobytes() == b[k].tobytes() for k in a
    )
