"""Proprioception and the vestibular sense, read straight from MuJoCo's arrays."""

from __future__ import annotations

from collections.abc import Callable

import mujoco
import numpy as np

LIMIT_ZONE = 0.035  # rad: limit proximity rises from 0 to 1 over the last 0.035 rad (facts 2)


class Proprioception:
    """Joint positions, velocities, torques, limit proximity, actions and motor torques.

    The vector is [qpos, qvel, torque, limit, action, motor], each (J,) for the J
    actuated joints in actuator order, so (6 J,) float32: 180 in the crib, 102 sitting.
    "torque" is the net torque the joint passes on (motor + passive spring-damper + constraint
    forces such as limits and contacts); "limit" is 0 until within 0.035 rad of a joint limit,
    rising linearly to 1 at the limit; "motor" is the applied motor torque, max_torque * action.

    Args:
        model: The compiled model.
        joints: The actuated joints' names, in actuator order.
        compiled: Gather with the compiled routine (:func:`devlearn.infant.kernels.gather`,
            imported with numba on first use); False: always :meth:`reference` (numpy only).
    """

    def __init__(self, model: mujoco.MjModel, joints: list[str], compiled: bool = True) -> None:
        self.compiled = compiled
        # the compiled routine, imported (numba) on first use
        self._gather: Callable[..., None] | None = None
        ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in joints]
        self.qpos = np.array([model.jnt_qposadr[j] for j in ids])
        self.dof = np.array([model.jnt_dofadr[j] for j in ids])
        self.lo, self.hi = model.jnt_range[ids, 0], model.jnt_range[ids, 1]
        self.size = 6 * len(ids)

    def __call__(self, data: mujoco.MjData) -> np.ndarray:
        """Returns (6 J,) float32 (one compiled gather; the numbers of :meth:`reference`)."""
        ctrl = data.ctrl
        if not self.compiled or ctrl.shape[0] != len(self.dof):  # or other actuators
            return self.reference(data)
        if self._gather is None:
            from devlearn.infant.kernels import gather

            self._gather = gather
        out = np.empty(self.size, dtype=np.float32)
        self._gather(
            data.qpos, data.qvel, data.qfrc_actuator, data.qfrc_passive, data.qfrc_constraint,
            ctrl, self.qpos, self.dof, self.lo, self.hi, LIMIT_ZONE, out,
        )  # fmt: skip
        return out

    def reference(self, data: mujoco.MjData) -> np.ndarray:
        """The same (6 J,) float32 vector in numpy (the equivalence test's reference)."""
        q = data.qpos.take(self.qpos)
        to_limit = np.minimum(q - self.lo, self.hi - q)
        limit = np.maximum(1.0 - to_limit / LIMIT_ZONE, 0.0)
        np.minimum(limit, 1.0, out=limit)
        motor = data.qfrc_actuator.take(self.dof)  # gear * ctrl: the motor's joint torque
        torque = motor + data.qfrc_passive.take(self.dof) + data.qfrc_constraint.take(self.dof)
        parts = [q, data.qvel.take(self.dof), torque, limit, data.ctrl, motor]
        return np.concatenate(parts).astype(np.float32)


def vestibular(data: mujoco.MjData) -> np.ndarray:
    """Head accelerometer (m/s^2, includes gravity) and gyro (rad/s) in the head frame, (6,)."""
    return np.asarray(data.sensordata[:6], dtype=np.float32).copy()
