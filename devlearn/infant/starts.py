"""Episode starts: the scene's rest state, BabyBench's (rest + random kicks), random poses."""

from __future__ import annotations

import mujoco
import numpy as np

STARTS = ("babybench", "rest", "random")
"""How an episode starts (``Infant.reset``): ``babybench``, the scene's initial state (settled,
for scenes with ``settle_steps``) then :data:`KICK_STEPS` physics steps of uniform-random
actions, as every BabyBench episode starts (facts sec. 3b); ``rest``, the initial state alone
(the same every episode); ``random``, joint angles uniform within their ranges and toys
placed at random."""
KICK_STEPS = 10
"""Uniform-random-action physics steps of a ``babybench`` start (BabyBench's reset)."""

MAX_START_PENETRATION = 0.005
"""Deepest contact penetration (m) accepted for a random initial pose."""
TOY_AREA = ((0.2, 0.4), (-0.07, 0.07))
"""Floor area (x, y ranges, m) where a random start places the toy blocks: in front of the
sitting infant, between its legs (the lower legs' inner edges are at |y| = 0.094)."""


def place_toys(
    model: mujoco.MjModel,
    toys: np.ndarray,
    toy_pose: tuple[np.ndarray, np.ndarray],
    rng: np.random.Generator | None,
) -> None:
    """Toy blocks at random in :data:`TOY_AREA` (``rng``), or at the scene's places (None).

    Args:
        model: The scene's model (its ``geom_pos`` and ``geom_quat`` are written).
        toys: Geom ids of the toy blocks (none: nothing is drawn, so scenes without toys
            keep their random streams).
        toy_pose: The blocks' scene positions and orientations (the places to return to).
        rng: Draws the positions and yaws; None: the scene's places.
    """
    if not len(toys):
        return
    pos, quat = (a.copy() for a in toy_pose)
    if rng is not None:
        (x0, x1), (y0, y1) = TOY_AREA
        n = len(toys)
        pos[:, 0], pos[:, 1] = rng.uniform(x0, x1, n), rng.uniform(y0, y1, n)
        yaw = rng.uniform(-np.pi, np.pi, n)
        quat[:] = 0.0
        quat[:, 0], quat[:, 3] = np.cos(yaw / 2), np.sin(yaw / 2)
    model.geom_pos[toys] = pos
    model.geom_quat[toys] = quat


def random_pose(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    qpos_index: np.ndarray,
    ranges: np.ndarray,
    rng: np.random.Generator,
    tries: int = 20,
) -> None:
    """Joint angles uniform within their ranges, avoiding poses that start buried.

    A uniform pose can put a limb deep inside the mattress or the body; the push-out
    then reaches thousands of newtons per sensor. Up to ``tries`` poses are drawn and the
    first whose deepest contact penetrates less than :data:`MAX_START_PENETRATION` is kept
    (else the least-penetrating one), so the pose stays random within the ranges.

    Args:
        model, data: The scene's physics (``data.qpos`` is written and forwarded).
        qpos_index: The actuated joints' ``qpos`` addresses.
        ranges: (joints, 2) their angle ranges.
        rng: Draws the angles.
        tries: Poses drawn at most.
    """
    best_pose, best_depth = None, np.inf
    for _ in range(tries):
        pose = rng.uniform(ranges[:, 0], ranges[:, 1])
        data.qpos[qpos_index] = pose
        mujoco.mj_forward(model, data)
        ncon = data.ncon
        depth = float(-data.contact.dist[:ncon].min()) if ncon else 0.0
        if depth < best_depth:
            best_pose, best_depth = pose, depth
        if depth < MAX_START_PENETRATION:
            return
    data.qpos[qpos_index] = best_pose
    mujoco.mj_forward(model, data)


def kick(model: mujoco.MjModel, data: mujoco.MjData, rng: np.random.Generator, steps: int) -> None:
    """``steps`` physics steps, each with fresh actions uniform in [-1, 1] (``data.ctrl``), then
    the controls back to zero: BabyBench's reset after restoring its initial state.

    Args:
        model, data: The scene's physics (stepped in place).
        rng: Draws the actions, (steps, nu) values.
        steps: Physics steps.
    """
    for _ in range(steps):
        data.ctrl[:] = rng.uniform(-1.0, 1.0, model.nu)
        mujoco.mj_step(model, data)
    data.ctrl[:] = 0.0
