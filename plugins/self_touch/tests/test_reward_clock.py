"""The self-touch reward's clock in simulated seconds (issue #57): the repeat pay's crossing and
time constant and the episode's length, converted with the physics step; the paper's step
counts kept; saved runs as trained; whole evaluation sessions."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from devlearn_self_touch import SelfTouch, SelfTouchConfig, TouchNovelty
from self_touch_fakes import ScriptedInfant

from devlearn import BatchContext, StepContext, UsageError
from devlearn.testing import (
    Play,
    PluginRegistry,
    config_round_trip,
    load_saved_config,
    run_command,
    run_config,
)

ROOT = Path(__file__).resolve().parents[3]
PUBLISHED = ROOT / "results/self_touch/i30/curriculum/two_stage/seed=4"


def held_pay(term: TouchNovelty, steps: int, physics_timestep: float | None) -> list[float]:
    """Touch novelty's pay, step by step, for one region touched on every step by a body
    whose physics step is ``physics_timestep`` (None: contexts without an infant)."""
    infant = (
        None if physics_timestep is None else SimpleNamespace(physics_timestep=physics_timestep)
    )
    touched = np.zeros(68, dtype=bool)
    touched[3] = True
    facts = {"touched": touched}
    return [
        float(term(BatchContext([StepContext(infant, {}, facts, t, False)]))[0])
        for t in range(steps)
    ]


def touch_novelty(config: SelfTouchConfig) -> TouchNovelty:
    term = SelfTouch(config).reward_terms()[0]
    assert isinstance(term, TouchNovelty)
    return term


def test_the_paper_preset_keeps_the_papers_step_counts_exactly():
    paper = run_config(SelfTouch, preset="paper").behavior
    assert (paper.touch_count, paper.repeat_crossing_s, paper.repeat_steepness_s) == (
        "step",
        0.05,
        0.01,
    )
    in_seconds = touch_novelty(paper)
    pay = held_pay(in_seconds, 40, 0.005)
    assert (in_seconds.midpoint, in_seconds.rate) == (10.0, 0.5)  # exactly, at 200 Hz
    in_steps = SelfTouchConfig(touch_count="step", repeat_crossing_s=None, repeat_steepness_s=None)
    assert pay == held_pay(touch_novelty(in_steps), 40, 0.005)  # bit for bit
    assert pay[10] == 0.0 and pay[9] > 0 > pay[11]  # the 11th step crosses: c = 10


def test_the_repeat_pay_crosses_at_the_same_time_whatever_the_physics_step():
    config = SelfTouchConfig(touch_count="step")
    for dt, crossing in ((0.005, 10), (0.0025, 20), (0.01, 5)):
        pay = held_pay(touch_novelty(config), 60, dt)
        assert pay[crossing] == pytest.approx(0.0, abs=1e-12), dt
        assert crossing * dt == pytest.approx(0.05)  # the same 0.05 s
        assert pay[crossing - 1] > 0 > pay[crossing + 1]
    # the pay at a given time is the same: 0.03 s into the contact at 200 and 400 Hz
    assert held_pay(touch_novelty(config), 13, 0.0025)[12] == pytest.approx(
        held_pay(touch_novelty(config), 7, 0.005)[6]
    )
    # counted in steps, a 400 Hz body would cross after half the time
    legacy = SelfTouchConfig(touch_count="step", repeat_crossing_s=None, repeat_steepness_s=None)
    assert held_pay(touch_novelty(legacy), 12, 0.0025)[10] == 0.0
    # a touch count is no time: with onset counting the seconds change nothing
    onset = [SelfTouchConfig(repeat_crossing_s=s, repeat_steepness_s=s) for s in (0.05, 0.5)]
    assert held_pay(touch_novelty(onset[0]), 30, 0.0025) == held_pay(
        touch_novelty(onset[1]), 30, 0.0025
    )


class HoldingInfant(ScriptedInfant):
    """The left hand on region 3 at every step of its 20-step episodes."""

    def hand_contacts(self) -> np.ndarray:
        contacts = np.zeros((2, 68), dtype=bool)
        contacts[0, 3] = True
        return contacts


def rewards(action_repeat: int, decisions: int) -> list[float]:
    behavior = SelfTouch(SelfTouchConfig(touch_count="step"))
    env = Play(behavior, infant_factory=HoldingInfant, action_repeat=action_repeat)
    env.reset()
    return [reward for [(_, reward, *_)] in env.play(decisions)]


def test_changing_the_decision_rate_keeps_the_reward_in_time():
    """Self-touch's rewards run at every physics step: a decision of 5 physics steps earns what
    its 5 steps earn at a decision per step (a clock of decisions would cross 5 times later)."""
    per_step = rewards(1, 40)
    per_decision = rewards(5, 8)
    sums = []
    for k in range(8):
        total = 0.0
        for r in per_step[5 * k : 5 * k + 5]:
            total += r
        sums.append(total)
    assert per_decision == sums


def test_the_episode_length_in_seconds():
    env = Play(SelfTouch(SelfTouchConfig(episode_s=0.06)), infant_factory=ScriptedInfant)
    assert env.episode_steps == 12  # 0.06 s of 5 ms steps, not the scripted infant's 20
    env.reset()
    infos = [info for [(*_, info)] in env.play(12)]
    assert infos[:-1] == [None] * 11 and infos[-1]["reward/balance"] == 10.0
    with pytest.raises(ValueError, match="episode_s must be above 0 seconds"):
        SelfTouch(SelfTouchConfig(episode_s=0.0))
    with pytest.raises(UsageError, match=r"self_touch's episode\(\).seconds: 0.0123 s is not"):
        Play(SelfTouch(SelfTouchConfig(episode_s=0.0123)), infant_factory=ScriptedInfant)


def test_saved_runs_keep_the_clock_they_were_trained_with():
    saved = json.loads((PUBLISHED / "config.json").read_text())
    assert "repeat_crossing_s" not in saved["behavior"]
    old = load_saved_config(saved, SelfTouch).behavior
    assert (old.repeat_crossing_s, old.repeat_steepness_s, old.episode_s) == (None, None, None)
    assert touch_novelty(old).clock is None  # the rewards table's counts
    new = config_round_trip(run_config(SelfTouch), SelfTouch).behavior
    assert (new.repeat_crossing_s, new.repeat_steepness_s, new.episode_s) == (0.05, 0.01, None)
    fresh = load_saved_config({"behavior": {}}, SelfTouch, run_config(SelfTouch)).behavior
    assert fresh.repeat_crossing_s == 0.05
    assert PluginRegistry().behavior("self_touch") is SelfTouch


def test_the_clock_refuses_half_a_setting_and_a_second_source():
    with pytest.raises(ValueError, match="set together \\(seconds\\) or both null"):
        SelfTouch(SelfTouchConfig(repeat_steepness_s=None))
    with pytest.raises(ValueError, match="must be above 0"):
        SelfTouch(SelfTouchConfig(repeat_crossing_s=-0.05))
    config = SelfTouchConfig(touch_count="step")
    config.rewards["touch_novelty"].params["midpoint"] = 12.0
    with pytest.raises(ValueError, match="repeat pay's clock is behavior.repeat_crossing_s"):
        SelfTouch(config)
    config.repeat_crossing_s = config.repeat_steepness_s = None  # in steps: allowed
    assert touch_novelty(config).midpoint == 12.0
    onset = SelfTouchConfig()  # the table's midpoint counts touches
    onset.rewards["touch_novelty"].params["midpoint"] = 12.0
    assert touch_novelty(onset).midpoint == 12.0


def test_devlearn_eval_refuses_a_session_of_part_of_a_step(tmp_path):
    result = run_command(
        "eval", "self_touch", "--policy", "zero", "--session", "0.0123", "--out", str(tmp_path)
    )
    assert result.code != 0
    assert "--session: 0.0123 s is not a whole number of physics steps" in result.err


@pytest.mark.slow
def test_a_one_second_session_from_rest(tmp_path):
    out = tmp_path / "eval"
    result = run_command(
        "eval", "self_touch", "--policy", "zero", "--session", "1", "--start", "rest",
        "--episodes", "1", "--out", str(out),
    )  # fmt: skip
    assert result.code == 0, result.err
    assert "1 sessions of 1 s from rest starts" in result.out
    summary = json.loads((out / "eval.json").read_text())
    assert summary["protocol"]["session_s"] == 1.0 and summary["episodes"] == 1
    assert summary["start"] == "rest"
    coded = summary["likeness_coded"]
    assert coded["coded_seconds"] == pytest.approx(1.0 - 10 * 0.005)  # after the settle steps
    assert coded["episodes"] == 1 and "episode_coverage_left_mean" in summary
