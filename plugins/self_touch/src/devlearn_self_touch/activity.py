"""Reward terms on how much the body moves and how long and how often it touches itself, not
on what it touches (issue #57's infant-like variants): a rest drive toward a preferred activity
level, an effort cost, a cost on the time a hand lies on the body, and a cost per touch.

The first three are costs per simulated second: a term called at every physics step of ``dt``
seconds pays its rate times ``dt``, so a second costs the same at any physics step or decision
rate (``env.action_repeat``), as the touch terms' clock in seconds (``repeat_crossing_s``). The
fourth is a cost per event (a touch as a video coder counts it), whose gap is in seconds too.
The first two read the body (``ctx.infant``: its joint or hand velocities, the controls it
applied), which the touch facts do not carry. All are off (weight 0) in the default reward
table and left out of the run while they are.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from devlearn import BatchContext, BatchedIntrinsicReward
from devlearn_self_touch.coding import contact_bodies, limb_contacts, model_body_codes

ACTIVITY_SIGNALS = ("hand_speed", "joint_speed")
"""What :class:`ActivityLevel` measures: ``hand_speed``, the mean linear speed of the two
hands' centres of mass (m/s), or ``joint_speed``, the mean absolute velocity of the actuated
joints (rad/s)."""

HAND_BODIES = ("left_hand", "right_hand")
"""The bodies whose speed ``hand_speed`` averages (the palms; the fingers move with them)."""


def bodies(batch: BatchContext, term: str) -> tuple[list[Any], float]:
    """The batch's bodies (one infant per env) and their physics step in seconds (every env's
    is the same).

    Raises:
        ValueError: A context carries no infant (the term reads the body).
    """
    infants = [ctx.infant for ctx in batch.contexts if ctx.infant is not None]
    if len(infants) < len(batch.contexts):
        raise ValueError(f"the {term} term reads the body: its step contexts need an infant")
    return infants, float(infants[0].physics_timestep)


def hand_speed(infant: Any) -> float:
    """The two hands' mean linear speed (m/s): their centres of mass's, from MuJoCo's body
    velocities (``mj_objectVelocity``, computed as the physics step began)."""
    import mujoco

    model, data = infant.model, infant.data
    velocity = np.zeros(6)
    total = 0.0
    for name in HAND_BODIES:
        body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
        # [rotation (3), translation (3)] at the body's centre of mass, world coordinates
        mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_BODY, body, velocity, 0)
        total += math.sqrt(float(velocity[3:] @ velocity[3:]))
    return total / len(HAND_BODIES)


def joint_speed(infant: Any) -> float:
    """The actuated joints' mean absolute velocity (rad/s): proprioception's qvel block."""
    joints = int(infant.action_dim)
    qvel = np.asarray(infant.proprioception())[joints : 2 * joints]
    return float(np.abs(qvel).mean())


SIGNALS = {"hand_speed": hand_speed, "joint_speed": joint_speed}


class ActivityLevel(BatchedIntrinsicReward):
    """A rest drive: the body's recent activity is pulled toward a preferred level.

    Spisak, Hoffmann, O'Regan et al. (IEEE TCDS 2026, arXiv 2504.17939) obtain infant-like
    activity in a self-touch model with a preferred activity level (a rest drive) besides
    motor noise: being still and being frantic both cost. Here the activity m_t is a running
    mean of an instantaneous speed s_t (:data:`ACTIVITY_SIGNALS`) over ``time_constant_s``
    simulated seconds, and the term pays, per physics step of dt seconds::

        m_t = m_{t-1} + (1 - exp(-dt / time_constant_s)) (s_t - m_{t-1}),   m = 0 at a reset
        r_t = -|m_t - preferred| * dt

    so a second away from the preferred level by d costs d (times the weight), whatever the
    physics step. m starts at 0 every episode: an episode starts from a still body (its
    initial velocities are zero, in rest and random poses alike).

    Args:
        weight: Term weight (0 in the default table: off).
        preferred: The preferred activity, in the signal's unit (m/s or rad/s).
        time_constant_s: The running mean's time constant (simulated seconds).
        signal: ``hand_speed`` or ``joint_speed``.
    """

    name = "activity_level"

    def __init__(
        self,
        weight: float = 1.0,
        preferred: float = 0.1,
        time_constant_s: float = 1.0,
        signal: str = "hand_speed",
    ) -> None:
        super().__init__(weight)
        if signal not in SIGNALS:
            raise ValueError(
                f"unknown activity signal '{signal}'; valid: {', '.join(ACTIVITY_SIGNALS)}"
            )
        if not (math.isfinite(preferred) and preferred >= 0):
            raise ValueError(f"activity preferred must be 0 or above, got {preferred}")
        if not (math.isfinite(time_constant_s) and time_constant_s > 0):
            raise ValueError(
                f"activity time_constant_s must be above 0 seconds, got {time_constant_s}"
            )
        self.preferred, self.time_constant_s = float(preferred), float(time_constant_s)
        self.signal = signal
        self._speed = SIGNALS[signal]
        self.bind(1)

    def bind(self, num_envs: int) -> None:
        super().bind(num_envs)
        self.activity = np.zeros(num_envs)
        """(num_envs,): each env's running mean m of the signal."""

    def __call__(self, batch: BatchContext) -> np.ndarray:
        infants, dt = bodies(batch, self.name)
        speed = np.array([self._speed(infant) for infant in infants])
        self.activity += -math.expm1(-dt / self.time_constant_s) * (speed - self.activity)
        return -np.abs(self.activity - self.preferred) * dt

    def reset(self, env: int) -> None:
        self.activity[env] = 0.0


class Effort(BatchedIntrinsicReward):
    """An effort cost: the squared motor command, per second.

    Effort (energy) costs are the usual account of why movements are smooth and economical
    (minimum-effort and optimal-feedback-control models, Todorov and Jordan, Nat. Neurosci.
    5:1226, 2002) and one of the drives issue #57 lists for infant-like activity. The command
    u (action_dim,) is what the motors applied this step (``infant.data.ctrl``: the policy's
    action, plus the motor noise where it is on, clipped to [-1, 1]; torque = max torque *
    u), and the term pays, per physics step of dt seconds::

        r_t = -mean_i(u_i^2) * dt

    so holding every motor at full torque for a second costs 1 (times the weight), whatever
    the physics step or the number of motors.

    Args:
        weight: Term weight (0 in the default table: off).
    """

    name = "effort"

    def __init__(self, weight: float = 1.0) -> None:
        super().__init__(weight)
        self.bind(1)

    def __call__(self, batch: BatchContext) -> np.ndarray:
        infants, dt = bodies(batch, self.name)
        effort = [float(np.mean(np.square(infant.data.ctrl))) for infant in infants]
        return -np.array(effort) * dt


class ContactTime(BatchedIntrinsicReward):
    """A cost on the time a hand lies on the body, per second, after a free start (issue #57).

    Under the video-coding protocol the paper's reward keeps a hand on the body 93% of a
    5-minute session, in bouts of ~14 s (``results/self_touch/likeness/``); infants touch the
    body about half the time and spend the rest moving between touches (DiMercurio et al.
    2018, abstract). The paper's repeat penalty does not reach a resting hand: it counts the
    regions whose force crosses the touch threshold, and a hand resting lightly touches none.
    This term counts contact itself: for each hand h touching any body region this step
    (``facts["hand_contacts"][h].any()``), with b_h the simulated seconds its current bout has
    lasted (0 at its first step), it pays, per physics step of dt seconds::

        r_t = -sum_h [b_h >= free_s] * dt

    so a touch shorter than ``free_s`` is free and a hand held on the body costs 1 a second
    (times the weight) after that, whatever the physics step. A bout ends at the first step the
    hand touches nothing; bouts start afresh every episode.

    Args:
        weight: Term weight (0 in the default table: off).
        free_s: The free start of each bout (simulated seconds).
    """

    name = "contact_time"

    def __init__(self, weight: float = 1.0, free_s: float = 0.5) -> None:
        super().__init__(weight)
        if not (math.isfinite(free_s) and free_s >= 0):
            raise ValueError(f"contact_time free_s must be 0 seconds or above, got {free_s}")
        self.free_s = float(free_s)
        self.bind(1)

    def bind(self, num_envs: int) -> None:
        super().bind(num_envs)
        self.bout = np.zeros((num_envs, 2))
        """(num_envs, 2): each hand's current bout on the body so far, in seconds (0: none)."""

    def __call__(self, batch: BatchContext) -> np.ndarray:
        _, dt = bodies(batch, self.name)
        on = batch.stack("hand_contacts", bool).any(axis=2)  # (num_envs, 2)
        paid = on & (self.bout >= self.free_s - 1e-12)
        self.bout = np.where(on, self.bout + dt, 0.0)
        return -paid.sum(axis=1) * dt

    def reset(self, env: int) -> None:
        self.bout[env] = 0.0


class TouchOnset(BatchedIntrinsicReward):
    """A cost per touch: each new bout of a hand on the body pays -1, as a video coder counts it
    (issue #57).

    Under the video-coding protocol (:mod:`devlearn_self_touch.coding`: 30 frames a second, gaps
    shorter than two frames merged) the contact cost's policies touch 150 times a minute in
    0.4-s bouts: :class:`ContactTime` leaves each bout's first ``free_s`` free, so short
    frequent touches cost nothing (``results/self_touch/likeness/``); infants touch at most ~40
    times a minute (DiMercurio et al. 2018, abstract). This term prices the touch itself: for
    each hand h that touches a body region this step (``facts["hand_contacts"][h].any()``), or
    with ``surface`` the body or the surface (the mattress, the crib: the coder's body and
    surface contacts, ``all_touches_per_minute``, from the infant's contact list), after
    touching none for at least ``min_gap_s`` simulated seconds (the coder's merge: a shorter
    gap continues the bout), it pays::

        r_t = -sum_h onset_h

    so every touch a coder would count costs 1 (times the weight), whatever the physics step or
    the decision rate. A hand touching at an episode's first step starts a bout there; bouts
    start afresh every episode. Body contacts alone (the fourth pilot) moved the touches onto
    the mattress, where they were free: ``surface`` counts them too.

    Args:
        weight: Term weight (0 in the default table: off).
        min_gap_s: The shortest gap off the body that ends a bout (simulated seconds; the
            coding protocol's two frames at 30 Hz by default).
        surface: Count touches of the surface too (False: the body's only).
    """

    name = "touch_onset"

    def __init__(
        self, weight: float = 1.0, min_gap_s: float = 2 / 30, surface: bool = False
    ) -> None:
        super().__init__(weight)
        if not (math.isfinite(min_gap_s) and min_gap_s >= 0):
            raise ValueError(f"touch_onset min_gap_s must be 0 seconds or above, got {min_gap_s}")
        if not isinstance(surface, bool):
            raise ValueError(f"touch_onset surface must be true or false, got {surface!r}")
        self.min_gap_s, self.surface = float(min_gap_s), surface
        self._codes: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self.bind(1)

    def _on_surface(self, infant: Any) -> np.ndarray:
        """(2,) bool: each hand touches something that is not the infant this step."""
        pairs = contact_bodies(infant)
        if pairs is None:
            raise ValueError("touch_onset with surface reads the contact list: it needs an infant")
        model = infant.model
        codes = self._codes.get(id(model))
        if codes is None:  # once per body (a growing body is rebuilt)
            codes = model_body_codes(model)
            if len(self._codes) > 64:  # bodies built and gone: keep the cache small
                self._codes.clear()
            self._codes[id(model)] = codes
        return limb_contacts(pairs, *codes)[1][:2]

    def bind(self, num_envs: int) -> None:
        super().bind(num_envs)
        self.off = np.full((num_envs, 2), np.inf)
        """(num_envs, 2): seconds since each hand last touched the body (inf: not this episode)."""

    def __call__(self, batch: BatchContext) -> np.ndarray:
        infants, dt = bodies(batch, self.name)
        on = batch.stack("hand_contacts", bool).any(axis=2)  # (num_envs, 2)
        if self.surface:
            on = on | np.stack([self._on_surface(infant) for infant in infants])
        onset = on & (self.off >= self.min_gap_s - 1e-12)
        self.off = np.where(on, 0.0, self.off + dt)
        return -onset.sum(axis=1).astype(float)

    def reset(self, env: int) -> None:
        self.off[env] = np.inf
