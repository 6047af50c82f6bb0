"""Batched and per-environment self_touch terms give identical rewards on the same steps."""

from __future__ import annotations

import numpy as np
import pytest
from devlearn_self_touch import SelfTouch, SelfTouchConfig
from per_env_rewards import per_env_reward_terms
from self_touch_fakes import ScriptedInfant, same_info

from devlearn import StepContext
from devlearn.testing import Play


def recorded_steps(rng, num_envs: int, steps: int, episode: int):
    """Random facts as a behaviour would produce them: per step, one context per env.

    Touches are sparse and repeat (held contacts), so every branch of every term is used:
    first ever, first in episode, repeats up to and past the f_decay midpoint, milestones.
    """
    held = rng.random((num_envs, 68)) < 0.05
    for t in range(steps):
        held ^= rng.random((num_envs, 68)) < 0.03
        contexts = []
        for e in range(num_envs):
            hands = (rng.random((2, 68)) < 0.04) | (held[e] & (rng.random((2, 68)) < 0.5))
            parts = np.zeros((2, 34), bool)
            for h in range(2):
                parts[h, np.flatnonzero(hands[h]) % 34] = True
            facts = {"touched": held[e] | hands.any(0), "hand_contacts": hands, "hand_parts": parts}
            contexts.append(StepContext(None, {}, facts, t % episode, t % episode == episode - 1))
        yield contexts


PER_ENV = "per_env"


def _with_min_parts(config: SelfTouchConfig, parts: int) -> SelfTouchConfig:
    config.rewards["balance"].params["min_parts"] = parts
    return config


# the per-environment twins keep per-environment lifetime memory


@pytest.mark.parametrize(
    "config",
    [
        SelfTouchConfig(lifetime_memory=PER_ENV),
        _with_min_parts(SelfTouchConfig(lifetime_memory=PER_ENV), 4),
    ],
)
def test_batched_terms_equal_per_env_terms_bit_for_bit(config):
    num_envs, episode = 5, 40
    behavior = SelfTouch(config)
    batched = behavior.reward_terms()
    for term in batched:
        term.bind(num_envs)
    per_env = [per_env_reward_terms(behavior.config) for _ in range(num_envs)]
    assert [t.name for t in batched] == [t.name for t in per_env[0]]
    totals = np.zeros((len(batched), num_envs))
    for contexts in recorded_steps(np.random.default_rng(3), num_envs, 6 * episode, episode):
        for k, term in enumerate(batched):
            values = term.weight * np.asarray(term(_batch(contexts)))
            expected = [e[k].weight * float(e[k](ctx)) for e, ctx in zip(per_env, contexts)]
            assert values.tolist() == expected, term.name  # exact, not approximate
            totals[k] += values
        if contexts[0].last_step:
            for i in range(num_envs):
                for term, own in zip(batched, per_env[i]):
                    assert _same_state(term.state_dict(i), own.state_dict())
                    term.reset(i)
                    own.reset()
    assert np.all(totals != 0), totals  # every term paid (or, held touches, cost) something


def _batch(contexts):
    from devlearn import BatchContext

    return BatchContext(contexts)


def _same_state(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)


class PerEnvSelfTouch(SelfTouch):
    """SelfTouch with today's per-environment terms (the reference)."""

    def reward_terms(self):
        return per_env_reward_terms(self.config)


def test_envs_log_the_same_sums_with_either_form():
    """Played in a batch and one env at a time: same rewards, reward/<term> sums, state."""

    def factory(k):
        return lambda scene, senses=(): ScriptedInfant(scene, senses, left=12 - k, right=9 + k)

    config = SelfTouchConfig(lifetime_memory=PER_ENV)
    batch = Play(SelfTouch(config), seeds=[0, 1, 2], infant_factory=[factory(k) for k in range(3)])
    reference = [Play(PerEnvSelfTouch(config), seed=k, infant_factory=factory(k)) for k in range(3)]
    batch.reset()
    for env in reference:
        env.reset()
    ends = 0
    for _ in range(3 * ScriptedInfant.episode_steps):
        got = batch.step(np.zeros((3, 4)))
        want = [env.step(np.zeros(4))[0] for env in reference]
        for (_, r1, d1, _, i1), (_, r2, d2, _, i2) in zip(got, want):
            assert (r1, d1) == (r2, d2) and same_info(i1, i2)
            ends += i1 is not None
    assert ends == 9
    for a, b in zip(batch.state(), reference):
        assert all(
            _same_state(x, y) for x, y in zip(a["terms"].values(), b.state()[0]["terms"].values())
        )


@pytest.mark.parametrize("memory, rows", [(PER_ENV, 3), ("shared", 1)])
def test_worker_batches_share_one_instance_per_term(memory, rows):
    envs = Play(
        SelfTouch(SelfTouchConfig(lifetime_memory=memory)), 3, infant_factory=ScriptedInfant
    )
    assert envs.reward_terms[0].num_envs == 3  # one instance of each term for the batch
    assert envs.reward_terms[0].ever.shape == (rows, 68)
    envs.reset()
    values = envs.term_values(np.zeros((3, 4)))
    assert list(values) == [t.name for t in envs.reward_terms]
    assert all(v.shape == (3,) for v in values.values()) and len(values) == 4
