"""Issue #57's infant-like terms: the rest drive (a preferred activity level) and the effort
cost, against hand-computed numbers, per simulated second, off by default."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from devlearn_self_touch import ActivityLevel, Effort, SelfTouch, SelfTouchConfig
from devlearn_self_touch.activity import hand_speed, joint_speed

from devlearn import BatchContext, StepContext, UsageError
from devlearn.testing import (
    crib_infant,  # noqa: F401 (a fixture)
    run_config,
)


class MovingBody:
    """Just the body the terms read: joint velocities (proprioception's second block of
    ``action_dim``) and the applied controls."""

    def __init__(self, dt: float = 0.005, action_dim: int = 2) -> None:
        self.physics_timestep, self.action_dim = dt, action_dim
        self.qvel = np.zeros(action_dim)
        self.data = SimpleNamespace(ctrl=np.zeros(action_dim))

    def proprioception(self) -> np.ndarray:
        blocks = [np.full(self.action_dim, 9.0), self.qvel, np.full(4 * self.action_dim, 7.0)]
        return np.concatenate(blocks).astype(np.float32)


def play(term, bodies: list[MovingBody]) -> np.ndarray:
    """One call of a batched term over ``bodies`` (one env each): (num_envs,)."""
    if term.num_envs != len(bodies):
        term.bind(len(bodies))
    contexts = [StepContext(body, {}, {}, 0, False) for body in bodies]
    return term(BatchContext(contexts))


def test_the_activity_is_a_running_mean_and_both_still_and_frantic_cost():
    term = ActivityLevel(preferred=1.0, time_constant_s=0.02, signal="joint_speed")
    body = MovingBody(dt=0.005)
    k = 1 - math.exp(-0.005 / 0.02)  # the mean's step at 200 Hz with a 20 ms time constant
    body.qvel[:] = [2.0, -2.0]  # |qvel| mean 2 rad/s
    m, expected = 0.0, []
    for _ in range(3):
        m += k * (2.0 - m)
        expected.append(-abs(m - 1.0) * 0.005)
    assert [float(play(term, [body])[0]) for _ in range(3)] == pytest.approx(expected)
    # frantic: the mean tends to 2, one unit above the preferred 1: -1 per second
    for _ in range(400):
        value = float(play(term, [body])[0])
    assert value == pytest.approx(-1.0 * 0.005, rel=1e-6)
    # still: back toward 0, one unit below: the same cost
    body.qvel[:] = 0.0
    for _ in range(400):
        value = float(play(term, [body])[0])
    assert value == pytest.approx(-1.0 * 0.005, rel=1e-6)
    # at the preferred level: no cost
    body.qvel[:] = [1.5, 0.5]
    for _ in range(400):
        value = float(play(term, [body])[0])
    assert value == pytest.approx(0.0, abs=1e-9)
    # a reset: the body starts still again
    term.reset(0)
    assert term.activity[0] == 0.0


def test_the_activity_cost_is_per_second_whatever_the_physics_step():
    # one second at 2 rad/s from still, preferred 0.5, a time constant of 0.25 s: at 200 and
    # 400 Hz the cost is (a Riemann sum of) one integral, of |2 (1 - exp(-t / 0.25)) - 0.5|
    def one_second(dt):
        term = ActivityLevel(preferred=0.5, time_constant_s=0.25, signal="joint_speed")
        body = MovingBody(dt=dt)
        body.qvel[:] = 2.0
        return sum(float(play(term, [body])[0]) for _ in range(round(1 / dt)))

    t = np.linspace(0, 1, 200_001)
    integral = -np.trapezoid(np.abs(2 * (1 - np.exp(-t / 0.25)) - 0.5), t)
    assert one_second(0.005) == pytest.approx(integral, rel=0.01)
    assert one_second(0.0025) == pytest.approx(integral, rel=0.005)


def test_the_activity_is_kept_per_env():
    term = ActivityLevel(preferred=0.0, time_constant_s=0.005, signal="joint_speed")
    still, moving = MovingBody(), MovingBody()
    moving.qvel[:] = 1.0
    values = play(term, [still, moving])
    assert values[0] == 0.0 and values[1] < 0
    term.reset(1)
    assert term.activity.tolist() == [0.0, 0.0]


def test_effort_is_the_mean_squared_command_per_second():
    term = Effort()
    body = MovingBody(dt=0.005, action_dim=3)
    body.data.ctrl = np.array([1.0, -0.5, 0.0])
    assert float(play(term, [body])[0]) == pytest.approx(-(1 + 0.25) / 3 * 0.005)
    body.data.ctrl = np.zeros(3)
    assert float(play(term, [body])[0]) == 0.0
    # full torque on every motor for a second costs 1, at any physics step
    for dt in (0.005, 0.002):
        body = MovingBody(dt=dt, action_dim=3)
        body.data.ctrl = np.ones(3)
        assert sum(float(play(term, [body])[0]) for _ in range(round(1 / dt))) == (
            pytest.approx(-1.0)
        )


def test_the_terms_need_the_body():
    batch = BatchContext([StepContext(None, {}, {}, 0, False)])
    for term in (Effort(), ActivityLevel()):
        with pytest.raises(ValueError, match="reads the body"):
            term(batch)


def test_hand_speed_is_the_hands_speed_in_the_world(crib_infant):  # noqa: F811
    # the arms swing under a constant command; the hands' speed is what the finite
    # differences of their centres of mass give (within the step's change of speed)
    infant = crib_infant
    infant.reset(np.random.default_rng(0), start="rest")
    assert hand_speed(infant) == pytest.approx(0.0, abs=1e-3)  # still at rest
    ids = [infant.model.body(name).id for name in ("left_hand", "right_hand")]
    action = np.zeros(infant.action_dim)
    for arm in ("left_arm", "right_arm"):
        action[infant.actuator_groups[arm]] = 0.8
    speeds, positions = [], []
    for _ in range(40):
        infant.step(action)
        speeds.append(hand_speed(infant))
        positions.append(infant.data.xipos[ids].copy())
    moved = np.linalg.norm(np.diff(np.array(positions), axis=0), axis=2).mean(axis=1)
    finite = moved / infant.physics_timestep  # (39,) m/s between consecutive steps
    assert max(speeds) > 0.05  # the hands moved
    np.testing.assert_allclose(speeds[1:], finite, rtol=0.1, atol=0.01)
    # joint speed: the actuated joints' mean |velocity| in rad/s
    qvel = infant.data.qvel[[infant.model.joint(j).dofadr[0] for j in infant.actuator_names]]
    assert joint_speed(infant) == pytest.approx(float(np.abs(qvel).mean()), rel=1e-5)


def test_the_terms_are_off_by_default_and_switched_on_from_the_config():
    names = [t.name for t in SelfTouch(SelfTouchConfig()).reward_terms()]
    assert names == ["touch_novelty", "contact_novelty", "diversity_milestones", "balance"]
    cfg = run_config(
        SelfTouch,
        [
            "behavior.rewards.activity_level.weight=2",
            "behavior.rewards.activity_level.params.preferred=0.3",
            "behavior.rewards.effort.weight=0.5",
        ],
    )
    terms = {t.name: t for t in SelfTouch(cfg.behavior).reward_terms()}
    assert list(terms)[-2:] == ["activity_level", "effort"]
    activity = terms["activity_level"]
    assert isinstance(activity, ActivityLevel) and isinstance(terms["effort"], Effort)
    assert (activity.weight, activity.preferred, activity.time_constant_s) == (2.0, 0.3, 1.0)
    assert terms["effort"].weight == 0.5
    # a paper term at weight 0 stays (logged, paying nothing), as before
    zero = run_config(SelfTouch, ["behavior.rewards.balance.weight=0"])
    assert "balance" in [t.name for t in SelfTouch(zero.behavior).reward_terms()]


def test_wrong_activity_options_name_the_valid_ones():
    with pytest.raises(ValueError, match="unknown activity signal 'hand'; valid: hand_speed"):
        ActivityLevel(signal="hand")
    with pytest.raises(ValueError, match="time_constant_s must be above 0"):
        ActivityLevel(time_constant_s=0)
    with pytest.raises(UsageError, match=r"valid: preferred, time_constant_s, signal"):
        run_config(SelfTouch, ["behavior.rewards.activity_level.params.tau=1"])
    # a run's config is refused before anything starts, with the term's own message
    with pytest.raises((UsageError, ValueError), match="valid: hand_speed, joint_speed"):
        run_config(SelfTouch, ["behavior.rewards.activity_level.params.signal=feet"])


def test_contact_time_costs_a_held_hand_after_its_free_start_per_second():
    """Issue #57: the paper's reward kept a hand on the body 93% of a session. Each hand's bout
    on the body is free for ``free_s`` seconds, then costs 1 a second; a step off the body ends
    the bout. At 200 Hz with free_s 0.02 (4 steps): the left hand held 6 steps pays 0, 0, 0, 0,
    -dt, -dt; both hands on: twice; a break restarts the free start."""
    from devlearn_self_touch import ContactTime

    term = ContactTime(free_s=0.02)
    term.bind(2)
    dt = 0.005
    body = MovingBody(dt=dt)

    def step(left: bool, right: bool) -> np.ndarray:
        contacts = np.zeros((2, 68), dtype=bool)
        contacts[0, 3], contacts[1, 40] = left, right
        facts = [{"hand_contacts": contacts}, {"hand_contacts": np.zeros((2, 68), bool)}]
        return term(BatchContext([StepContext(body, {}, f, 0, False) for f in facts]))

    paid = [step(True, False) for _ in range(6)]
    assert [float(p[0]) for p in paid] == pytest.approx([0, 0, 0, 0, -dt, -dt])
    assert all(float(p[1]) == 0 for p in paid)  # the other env touches nothing
    # the right hand joins: its own free start, then both cost
    both = [float(step(True, True)[0]) for _ in range(5)]
    assert both == pytest.approx([-dt, -dt, -dt, -dt, -2 * dt])
    # one step off the body ends the left hand's bout; the right hand's goes on
    assert float(step(False, True)[0]) == pytest.approx(-dt)
    assert float(step(True, True)[0]) == pytest.approx(-dt)
    term.reset(0)  # a new episode: every bout starts afresh
    assert float(step(True, True)[0]) == 0.0
    with pytest.raises(ValueError, match="free_s must be 0 seconds or above"):
        ContactTime(free_s=-1)


def test_contact_time_is_off_by_default_and_switched_on_from_the_config():
    from devlearn_self_touch import ContactTime

    cfg = run_config(
        SelfTouch,
        ["behavior.rewards.contact_time.weight=2", "behavior.rewards.contact_time.params.free_s=1"],
    )
    terms = {t.name: t for t in SelfTouch(cfg.behavior).reward_terms()}
    assert isinstance(terms["contact_time"], ContactTime)
    assert (terms["contact_time"].weight, terms["contact_time"].free_s) == (2.0, 1.0)
    assert "contact_time" not in [t.name for t in SelfTouch(SelfTouchConfig()).reward_terms()]


def test_touch_onset_costs_each_touch_a_coder_counts():
    """Issue #57: the contact cost's policies touch 150 times a minute in 0.4-s bouts. Each new
    bout of a hand on the body costs 1; a gap shorter than ``min_gap_s`` (the coder's merge)
    continues the bout and costs nothing; holding costs nothing; both hands count apart."""
    from devlearn_self_touch import TouchOnset

    term = TouchOnset(min_gap_s=0.015)  # 3 steps at 200 Hz
    term.bind(2)
    body = MovingBody(dt=0.005)

    def step(left: bool, right: bool) -> float:
        contacts = np.zeros((2, 68), dtype=bool)
        contacts[0, 3], contacts[1, 40] = left, right
        facts = [{"hand_contacts": contacts}, {"hand_contacts": np.zeros((2, 68), bool)}]
        paid = term(BatchContext([StepContext(body, {}, f, 0, False) for f in facts]))
        assert float(paid[1]) == 0.0  # the other env touches nothing
        return float(paid[0])

    assert [step(True, False) for _ in range(4)] == [-1.0, 0.0, 0.0, 0.0]  # one touch, held
    assert [step(False, False) for _ in range(2)] == [0.0, 0.0]  # 2 steps off: under the gap
    assert step(True, False) == 0.0  # the same bout, as the coder merges it
    assert [step(False, False) for _ in range(3)] == [0.0, 0.0, 0.0]  # 3 steps off: a gap
    assert step(True, True) == -2.0  # a new touch by each hand
    term.reset(0)  # a new episode: a hand already on the body starts a bout
    assert step(True, False) == -1.0
    with pytest.raises(ValueError, match="min_gap_s must be 0 seconds or above"):
        TouchOnset(min_gap_s=-1)
    cfg = run_config(SelfTouch, ["behavior.rewards.touch_onset.weight=3"])
    terms = {t.name: t for t in SelfTouch(cfg.behavior).reward_terms()}
    assert isinstance(terms["touch_onset"], TouchOnset) and terms["touch_onset"].weight == 3.0
    assert terms["touch_onset"].min_gap_s == pytest.approx(2 / 30)
    assert "touch_onset" not in [t.name for t in SelfTouch(SelfTouchConfig()).reward_terms()]


def test_touch_onset_with_surface_counts_the_mattress_as_the_coder_does():
    """The fourth pilot's body-only cost moved the touches onto the mattress (body 54-66 a
    minute, surface 106-117): with ``surface`` a hand's contact with anything that is not the
    infant is a touch too, and a hand going from the mattress to the body with no gap is one
    bout, as ``all_touches_per_minute`` codes it."""
    from devlearn_self_touch import TouchOnset

    names = ["world", "hip", "left_hand", "left_fingers", "right_hand"]
    ids = {name: b for b, name in enumerate(names)}

    class Infant:
        physics_timestep = 0.005
        model = SimpleNamespace(
            nbody=len(names),
            body=lambda b: SimpleNamespace(name=names[b]),
            geom_bodyid=np.arange(len(names)),
        )

        def touching(self, *pairs: tuple[str, str]) -> None:
            geom = np.array([[ids[a], ids[b]] for a, b in pairs], dtype=np.int64).reshape(-1, 2)
            self.data = SimpleNamespace(
                contact=SimpleNamespace(geom=geom, efc_address=np.zeros(len(geom), np.int64))
            )

    infant = Infant()
    body_only, both = TouchOnset(min_gap_s=0.01), TouchOnset(min_gap_s=0.01, surface=True)
    for term in (body_only, both):
        term.bind(1)

    def step(on_body: bool, *pairs: tuple[str, str]) -> tuple[float, float]:
        infant.touching(*pairs)
        contacts = np.zeros((2, 68), dtype=bool)
        contacts[0, 3] = on_body  # the left hand on a body region
        batch = BatchContext([StepContext(infant, {}, {"hand_contacts": contacts}, 0, False)])
        return float(body_only(batch)[0]), float(both(batch)[0])

    assert step(False, ("world", "left_fingers")) == (0.0, -1.0)  # on the mattress
    assert step(False, ("world", "left_fingers")) == (0.0, 0.0)  # held
    assert step(True, ("left_hand", "hip")) == (-1.0, 0.0)  # onto the body, no gap: one bout
    assert step(False, ("left_hand", "left_fingers")) == (0.0, 0.0)  # its own fingers: nothing
    step(False)
    assert step(False, ("right_hand", "world")) == (0.0, -1.0)  # the right hand on the mattress
    with pytest.raises(ValueError, match="surface must be true or false"):
        TouchOnset(surface="yes")  # type: ignore[arg-type]
