"""Generate the infant's MJCF (dm_control.mjcf) from the body table, mirroring left to right."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
from dm_control import mjcf

from devlearn.infant.body_table import (
    BODY_TABLE,
    EXCLUDED_PAIRS,
    EYE_RGBA,
    MITTEN_BODIES,
    MITTEN_RGBA,
    SIDES,
    SKIN_RGBA,
    BodySpec,
    spec_by_name,
)

BODY_CONTYPE = 1  # collision bit of body geoms; world geoms use bit 2 and collide with bit 1
WORLD_CONTYPE = 2


def mirror_point(p: Sequence[float]) -> tuple[float, ...]:
    """Mirror positions across the body's midline plane y = 0 (also 6-vectors like fromto)."""
    p = list(p)
    for i in range(1, len(p), 3):
        p[i] = -p[i]
    return tuple(p)


def mirror_axis(axis: Sequence[float]) -> tuple[float, float, float]:
    """Mirror a rotation axis (a pseudo-vector): (ax, ay, az) -> (-ax, ay, -az).

    With the axis mirrored this way the same joint angle gives the mirrored movement, so
    ranges, torques and actions are identical on both sides.
    """
    return (-axis[0], axis[1], -axis[2])


def axis_angle_quat(axis: Sequence[float], angle: float) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation by ``angle`` about ``axis``."""
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    return np.concatenate([[math.cos(angle / 2)], math.sin(angle / 2) * a])


def quat_mul(q1: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Hamilton product q1 * q2 of (w, x, y, z) quaternions."""
    w1, x1, y1, z1 = q1
    w2, x2, y2, z2 = q2
    return np.array(
        [
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        ]
    )


def _full(spec: BodySpec, side: str | None) -> str:
    return f"{side}_{spec.name}" if spec.paired else spec.name


def _parent_name(spec: BodySpec, side: str | None) -> str:
    parent = spec_by_name(spec.parent)
    return f"{side}_{parent.name}" if parent.paired else parent.name


def add_infant(
    root: mjcf.RootElement,
    *,
    root_pos: Sequence[float],
    root_quat: Sequence[float],
    actuated_groups: set[str],
    held: Mapping[str, float],
    vestibular: bool,
    hand_rgba: tuple[float, float, float, float] = MITTEN_RGBA,
    right_hand_rgba: tuple[float, float, float, float] | None = None,
    table: tuple[BodySpec, ...] = BODY_TABLE,
    density: float | None = None,
) -> list[str]:
    """Add the infant's bodies, joints, motors and contact exclusions to ``root``.

    The hand and fingers bodies are coloured ``hand_rgba`` (default: purple mittens; pass
    ``SKIN_RGBA`` for bare hands), or the right hand ``right_hand_rgba`` when given; every other
    body part skin, the eyes dark.

    Joints whose group is not in ``actuated_groups`` are locked: left out of the model, their
    body rotated by the held angle (``held``, keyed by full joint name "left_knee"; default 0).
    The root body ("hip") is fixed in the world (no free joint).

    ``table`` is the body to build (default: :data:`BODY_TABLE`; a grown body's is
    :attr:`devlearn.infant.growth.GrownBody.table`) and ``density`` the density of its geoms
    (kg/m^3; None: MuJoCo's default, 1000), from which MuJoCo computes masses and inertias.

    Returns:
        The actuated joint names, in actuator order.
    """
    bodies: dict[str, mjcf.Element] = {}
    actuated: list[str] = []
    mass = {} if density is None else {"density": density}
    for spec in table:
        for side in SIDES if spec.paired else (None,):
            right = side == "right"
            name = _full(spec, side)
            pos = mirror_point(spec.pos) if right else spec.pos
            quat = (
                np.asarray(root_quat, dtype=float) if not spec.parent else np.array([1.0, 0, 0, 0])
            )
            parent = root.worldbody if not spec.parent else bodies[_parent_name(spec, side)]
            moving = [j for j in spec.joints if j.group in actuated_groups]
            for joint in spec.joints:
                angle = held.get(f"{side}_{joint.name}" if side else joint.name, 0.0)
                if joint not in moving and angle != 0.0:
                    if moving:
                        raise ValueError(f"{name}: cannot hold {joint.name} while others move")
                    axis = mirror_axis(joint.axis) if right else joint.axis
                    quat = quat_mul(quat, axis_angle_quat(axis, angle))
            body = parent.add(
                "body", name=name, pos=root_pos if not spec.parent else pos, quat=quat
            )
            bodies[name] = body
            for joint in moving:
                jname = f"{side}_{joint.name}" if side else joint.name
                body.add(
                    "joint",
                    name=jname,
                    type="hinge",
                    axis=mirror_axis(joint.axis) if right else joint.axis,
                    range=joint.range,
                    limited=True,
                    stiffness=joint.stiffness,
                    damping=joint.damping,
                    armature=joint.armature,
                    frictionloss=joint.frictionloss,
                )
                root.actuator.add(
                    "motor",
                    name=jname,
                    joint=jname,
                    gear=[joint.max_torque],
                    ctrlrange=[-1.0, 1.0],
                    ctrllimited=True,
                )
                actuated.append(jname)
            for geom in spec.geoms:
                key, value = ("pos", geom.pos) if geom.fromto is None else ("fromto", geom.fromto)
                kwargs = {key: mirror_point(value) if right else value}
                collide = BODY_CONTYPE if spec.collides else 0
                body.add(
                    "geom",
                    name=f"{side}_{geom.name}" if side else geom.name,
                    type=geom.kind,
                    size=geom.size,
                    contype=collide,
                    conaffinity=collide,
                    rgba=_colour(spec, right_hand_rgba if right and right_hand_rgba else hand_rgba),
                    **kwargs,
                    **mass,
                )
            if spec.camera:
                # MuJoCo cameras look along their -z axis with +y up: look forward (+x), z up.
                body.add(
                    "camera",
                    name=name,
                    pos=(spec.camera_offset, 0.0, 0.0),
                    fovy=60,
                    xyaxes=(0, -1, 0, 0, 0, 1),
                )
            if spec.name == "head":
                head_centre = spec.geoms[0].pos
                body.add("site", name="vestibular", pos=head_centre, size=[0.005])
    if vestibular:
        root.sensor.add("accelerometer", name="head_accelerometer", site="vestibular")
        root.sensor.add("gyro", name="head_gyro", site="vestibular")
    # MuJoCo filters parent-child contacts only between moving bodies; in these scenes the hip
    # (and, sitting, the trunk and legs) are welded to the world, so exclude every such pair.
    family = [(spec.parent, spec.name) for spec in table if spec.parent and spec.collides]
    for a, b in family + list(EXCLUDED_PAIRS):
        pa, pb = spec_by_name(a).paired, spec_by_name(b).paired
        for side in SIDES:
            na = f"{side}_{a}" if pa else a
            nb = f"{side}_{b}" if pb else b
            if not (pa or pb) and side == "right":
                continue
            root.contact.add("exclude", body1=na, body2=nb)
    return actuated


def _colour(
    spec: BodySpec, hand_rgba: tuple[float, float, float, float]
) -> tuple[float, float, float, float]:
    """RGBA of a body's geoms: eyes dark, hands (and fingers) ``hand_rgba``, the rest skin."""
    if not spec.collides:
        return EYE_RGBA
    return hand_rgba if spec.name in MITTEN_BODIES else SKIN_RGBA
