"""The four reward terms against numbers computed by hand from the paper's formulas (II-A3)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from devlearn_self_touch.rewards import f_decay
from per_env_rewards import Balance, ContactNovelty, DiversityMilestones, TouchNovelty
from self_touch_fakes import make_ctx


def test_f_decay_values():
    assert f_decay(0) == pytest.approx(2 / (1 + math.exp(-5)) - 1)
    assert f_decay(0) == pytest.approx(0.98661, abs=1e-5)
    assert f_decay(10) == pytest.approx(0.0, abs=1e-12)
    assert f_decay(1) == pytest.approx(2 / (1 + math.exp(-4.5)) - 1)
    assert f_decay(20) == pytest.approx(2 / (1 + math.exp(5)) - 1)
    assert f_decay(200) == pytest.approx(-1.0, abs=1e-12)
    assert f_decay(1e6) == -1.0  # no overflow
    assert f_decay(11) < 0 < f_decay(9)


def test_touch_novelty_cases_and_episode_count():
    term = TouchNovelty()
    assert term(make_ctx(touched=[3])) == pytest.approx(5.0)  # first ever (c = 0 -> 1)
    assert term(make_ctx(touched=[3])) == pytest.approx(0.5 * f_decay(1))  # c = 1 before
    assert term(make_ctx(touched=[3, 7])) == pytest.approx(0.5 * f_decay(2) + 5.0)
    assert term(make_ctx(touched=[])) == 0.0
    assert term(make_ctx(touched=[3])) == pytest.approx(0.5 * f_decay(3))  # count, not streak
    term.reset()
    assert term(make_ctx(touched=[3, 7])) == pytest.approx(2 * 1.0)  # first in episode
    assert term(make_ctx(touched=[7])) == pytest.approx(0.5 * f_decay(1))


def test_touch_novelty_held_contact_turns_negative():
    term = TouchNovelty()
    rewards = [term(make_ctx(touched=[0])) for _ in range(30)]
    assert rewards[0] == 5.0
    assert rewards[10] == pytest.approx(0.0, abs=1e-12)  # c = 10 earlier steps
    assert rewards[9] > 0 > rewards[11]
    assert rewards[29] == pytest.approx(0.5 * f_decay(29))
    assert sum(rewards[1:]) == pytest.approx(sum(0.5 * f_decay(c) for c in range(1, 30)))


def test_touch_novelty_state_dict_keeps_first_ever_memory():
    term = TouchNovelty()
    term(make_ctx(touched=[5]))
    restored = TouchNovelty()
    restored.load_state_dict(term.state_dict())
    assert restored(make_ctx(touched=[5])) == 1.0  # known region, new episode
    assert restored(make_ctx(touched=[6])) == 5.0
    fresh = TouchNovelty()
    assert fresh(make_ctx(touched=[5])) == 5.0


def test_contact_novelty_first_global_then_first_in_episode():
    term = ContactNovelty()
    assert term(make_ctx(hand_contacts=[(0, 10)])) == 10.0
    assert term(make_ctx(hand_contacts=[(0, 10)])) == 0.0  # holding pays nothing
    assert term(make_ctx(hand_contacts=[(0, 10), (1, 10)])) == 10.0  # other hand is new
    term.reset()
    assert term(make_ctx(hand_contacts=[(0, 10), (1, 10), (1, 11)])) == 2.0 + 2.0 + 10.0
    assert term(make_ctx(hand_contacts=[])) == 0.0
    assert term(make_ctx(hand_contacts=[(0, 10)])) == 0.0  # already this episode


def test_contact_novelty_state_dict_round_trip():
    term = ContactNovelty()
    term(make_ctx(hand_contacts=[(1, 40)]))
    state = term.state_dict()
    restored = ContactNovelty()
    restored.load_state_dict(state)
    assert restored(make_ctx(hand_contacts=[(1, 40), (0, 40)])) == 2.0 + 10.0
    state["ever"][:] = False  # the saved state is a copy, not a view
    assert restored.ever[1, 40]


def test_milestones_each_paid_once_per_episode():
    term = DiversityMilestones()
    assert term(make_ctx(touched=range(4))) == 0.0
    assert term(make_ctx(touched=[4])) == 5.0  # 5 distinct regions
    assert term(make_ctx(touched=range(5))) == 0.0  # still 5: paid already
    assert term(make_ctx(touched=range(5, 10))) == 5.0  # 10
    assert term(make_ctx(touched=range(10, 30))) == 4 * 5.0  # 30 crosses 15, 20, 25, 30
    assert term(make_ctx(touched=range(30, 68))) == 0.0  # no milestone above 30
    term.reset()
    assert term(make_ctx(touched=range(68))) == 6 * 5.0
    total = DiversityMilestones()
    assert sum(total(make_ctx(touched=[j])) for j in range(68)) == 30.0


@pytest.mark.parametrize(
    ("n_left", "n_right", "expected"), [(5, 8, 10.0), (5, 9, 0.0), (9, 5, 0.0), (0, 0, 10.0)]
)
def test_balance_pays_on_last_step_only(n_left, n_right, expected):
    term = Balance()
    pairs = [(0, p) for p in range(n_left)] + [(1, p) for p in range(n_right)]
    assert term(make_ctx(hand_parts=pairs)) == 0.0
    assert term(make_ctx(hand_parts=pairs[:1], last_step=True)) == expected


def test_balance_accumulates_distinct_parts_over_the_episode():
    term = Balance(min_parts=1)
    for p in range(4):
        term(make_ctx(hand_parts=[(0, p), (0, p)]))
    assert term(make_ctx(hand_parts=[(1, 0)], last_step=True)) == 10.0  # |4 - 1| = 3
    term.reset()
    assert term(make_ctx(last_step=True)) == 0.0  # min_parts=1: idleness does not pay
    assert Balance()(make_ctx(last_step=True)) == 10.0  # the paper's rule (no minimum)


def test_terms_have_names_and_weights():
    terms = [TouchNovelty(2.0), ContactNovelty(), DiversityMilestones(), Balance()]
    assert [t.name for t in terms] == [
        "touch_novelty",
        "contact_novelty",
        "diversity_milestones",
        "balance",
    ]
    assert terms[0].weight == 2.0
    assert all(isinstance(t(make_ctx(touched=[1])), float) for t in terms[:1])
    assert np.all([isinstance(t.state_dict(), dict) for t in terms])
