"""The behaviour played as training plays it, with a scripted fake infant: per-episode sums."""

from __future__ import annotations

import numpy as np
import pytest
from devlearn_self_touch import SelfTouch
from self_touch_fakes import ScriptedInfant

from devlearn.testing import Play


def _run_episode(env: Play) -> dict[str, float]:
    for _ in range(ScriptedInfant.episode_steps):
        [(_, reward, done, _, info)] = env.step(np.zeros(ScriptedInfant.action_dim))
        assert np.isfinite(reward)
    assert done
    return info


def test_two_episodes_pay_what_the_paper_says():
    env = Play(SelfTouch(), seed=0, infant_factory=ScriptedInfant)
    env.reset()
    # 22 regions touched once each: left hand regions 0..11, right hand regions 34..43.
    first = _run_episode(env)
    assert first["reward/touch_novelty"] == pytest.approx(22 * 5.0)
    assert first["reward/contact_novelty"] == pytest.approx(22 * 10.0)
    assert first["reward/diversity_milestones"] == pytest.approx(4 * 5.0)  # 5, 10, 15, 20
    assert first["reward/balance"] == pytest.approx(10.0)  # |12 - 10| = 2 <= 3
    assert first["metrics/coverage_left"] == 12 and first["metrics/coverage_right"] == 10
    assert first["metrics/coverage_total"] == 12
    assert first["metrics/score"] == pytest.approx(22 / 68)
    second = _run_episode(env)
    assert second["reward/touch_novelty"] == pytest.approx(22 * 1.0)
    assert second["reward/contact_novelty"] == pytest.approx(22 * 2.0)
    assert second["reward/diversity_milestones"] == pytest.approx(20.0)
    # Resume: lifetime memory comes back, so a restored env pays "first in episode" only.
    state = env.state()
    resumed = Play(SelfTouch(), seed=1, infant_factory=ScriptedInfant)
    resumed.load_state(state)
    resumed.reset()
    assert _run_episode(resumed)["reward/contact_novelty"] == pytest.approx(22 * 2.0)


def test_unbalanced_hands_get_no_balance_bonus():
    def factory(scene, senses=()):
        return ScriptedInfant(scene, senses, left=12, right=8)

    env = Play(SelfTouch(), seed=0, infant_factory=factory)
    env.reset()
    info = _run_episode(env)
    assert info["reward/balance"] == 0.0  # |12 - 8| = 4 > 3
    assert info["metrics/coverage_right"] == 8
