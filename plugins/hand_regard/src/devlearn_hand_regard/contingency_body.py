"""Where the body says each hand is: the infant's kinematic chain as numbers, and each hand's
place in each eye image from the proprioception alone (issue #58).

The contingency attribution (:mod:`~devlearn_hand_regard.contingency`) asks, per decision,
where each arm's posture puts its hand in each eye. Issue #58's first rule learned that from
babbled postures (nearest neighbours, a quadratic regression) and was 5-20 px off on held-out
postures (a cubic in the arm's seven angles and the head's swivel: 6 px; measured), too coarse
to tell two hands apart where one crosses the midline. The body knows better: every joint of
the seated infant is actuated and sensed, so the hand's place is the forward kinematics of
the joint angles (the body schema). :func:`body_schema` reads the chain once from the
compiled MuJoCo model (each body's offset and rotation, each hinge's axis and anchor, the
mitten's geoms, the eye cameras' pose and field of view) into a small JSON-able dict;
:class:`BodySchema` evaluates it in numpy (no simulator at run time): each hand's centre in
pixels and its depth before each eye. On held-out babbling the projected centre lies within
about 1-2 px of the blob's centroid (median; hands more than 15 cm from the eye) and further
for hands close to the face or cut by the image's edge; babbling calibrates how far
(:func:`contingency.fit_contingency_model`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import mujoco

EYES = ("left_eye", "right_eye")
"""The eye cameras, in the detector's eye order."""
HAND_BODIES = (("left_hand", "left_fingers"), ("right_hand", "right_fingers"))
"""Per hand the bodies whose geoms make the mitten (their mean place is the hand's centre)."""


def _quaternion_matrix(q: np.ndarray) -> np.ndarray:
    """(3, 3) rotation of a unit quaternion [w, x, y, z] (MuJoCo's order)."""
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def _axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """(3, 3) rotation by ``angle`` (rad) about the unit ``axis`` (Rodrigues)."""
    x, y, z = axis
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def body_schema(
    model: mujoco.MjModel, actuated_joints: list[str], image_size: int = 64
) -> dict[str, Any]:
    """Read the kinematic chain from the eyes to the hands out of a compiled model.

    Args:
        model: The infant's compiled model (every joint a hinge; the seated scenes).
        actuated_joints: The proprioception's joints in its order (its first block holds
            their angles: ``Infant.actuator_names``).
        image_size: Pixels across an eye image.
    Returns:
        ``bodies``: per body (tree order, parents first) ``parent``, ``pos``, ``quat`` and its
        ``joints`` (``angle``: index into the proprioception, ``axis``, ``anchor``, ``zero``:
        the angle at which the body sits as defined); ``hands``: per hand its mitten's geoms
        (``body``, ``pos``); ``eyes``: per eye its camera's ``body``, ``pos``, ``quat`` and
        ``focal`` (pixels); ``image_size``.
    Raises:
        ValueError: A joint that is not a hinge, or a hinge the proprioception does not sense.
    """
    import mujoco

    angle_of = {name: i for i, name in enumerate(actuated_joints)}
    bodies = []
    for b in range(model.nbody):
        joints = []
        for j in range(model.body_jntadr[b], model.body_jntadr[b] + model.body_jntnum[b]):
            name = model.joint(j).name
            if model.jnt_type[j] != mujoco.mjtJoint.mjJNT_HINGE or name not in angle_of:
                raise ValueError(
                    f"joint '{name}' is not a sensed hinge: the body schema needs every joint "
                    f"actuated and sensed (seated scenes; sensed: {', '.join(actuated_joints)})"
                )
            joints.append(
                {
                    "angle": angle_of[name],
                    "axis": np.round(model.jnt_axis[j], 6).tolist(),
                    "anchor": np.round(model.jnt_pos[j], 6).tolist(),
                    "zero": round(float(model.qpos0[model.jnt_qposadr[j]]), 6),
                }
            )
        bodies.append(
            {
                "parent": int(model.body_parentid[b]),
                "pos": np.round(model.body_pos[b], 6).tolist(),
                "quat": np.round(model.body_quat[b], 6).tolist(),
                "joints": joints,
            }
        )
    hands = []
    for names in HAND_BODIES:
        ids = [model.body(name).id for name in names]
        hands.append(
            [
                {"body": int(model.geom_bodyid[g]), "pos": np.round(model.geom_pos[g], 6).tolist()}
                for g in range(model.ngeom)
                if model.geom_bodyid[g] in ids
            ]
        )
    eyes = []
    for name in EYES:
        cam = model.camera(name)
        fovy = float(model.cam_fovy[cam.id])
        eyes.append(
            {
                "body": int(model.cam_bodyid[cam.id]),
                "pos": np.round(model.cam_pos[cam.id], 6).tolist(),
                "quat": np.round(model.cam_quat[cam.id], 6).tolist(),
                "focal": round(0.5 * image_size / np.tan(np.deg2rad(fovy) / 2), 4),
            }
        )
    return {"bodies": bodies, "hands": hands, "eyes": eyes, "image_size": int(image_size)}


class BodySchema:
    """:func:`body_schema`'s chain, evaluated in numpy.

    Args:
        schema: :func:`body_schema`'s dict (as read back from JSON).
    """

    def __init__(self, schema: dict[str, Any]) -> None:
        self.parent = [int(b["parent"]) for b in schema["bodies"]]
        self.pos = [np.asarray(b["pos"], dtype=float) for b in schema["bodies"]]
        self.rotation = [_quaternion_matrix(b["quat"]) for b in schema["bodies"]]
        self.joints = [
            [
                (
                    int(j["angle"]),
                    np.asarray(j["axis"], dtype=float) / np.linalg.norm(j["axis"]),
                    np.asarray(j["anchor"], dtype=float),
                    float(j["zero"]),
                )
                for j in b["joints"]
            ]
            for b in schema["bodies"]
        ]
        self.hands = [
            [(int(g["body"]), np.asarray(g["pos"], dtype=float)) for g in hand]
            for hand in schema["hands"]
        ]
        self.eyes = [
            (
                int(e["body"]),
                np.asarray(e["pos"], dtype=float),
                _quaternion_matrix(e["quat"]),
                float(e["focal"]),
            )
            for e in schema["eyes"]
        ]
        self.image_size = int(schema["image_size"])
        self.angles = 1 + max((j[0] for b in self.joints for j in b), default=-1)

    def frames(self, angles: np.ndarray) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """Every body's world position and rotation at these joint angles (MuJoCo's
        ``mj_kinematics`` for hinges: a hinge turns its body about its anchor by the angle
        less its zero).

        Args:
            angles: (J,) the proprioception's joint angles (its first block).
        Returns:
            positions: per body (3,); rotations: per body (3, 3).
        """
        positions: list[np.ndarray] = []
        rotations: list[np.ndarray] = []
        for b, parent in enumerate(self.parent):
            if b == 0:
                positions.append(np.zeros(3))
                rotations.append(np.eye(3))
                continue
            p = positions[parent] + rotations[parent] @ self.pos[b]
            r = rotations[parent] @ self.rotation[b]
            for angle, axis, anchor, zero in self.joints[b]:
                pivot = p + r @ anchor
                r = r @ _axis_rotation(axis, float(angles[angle]) - zero)
                p = pivot - r @ anchor
            positions.append(p)
            rotations.append(r)
        return positions, rotations

    def project(self, proprioception: np.ndarray) -> np.ndarray:
        """Each hand's centre in each eye image.

        Args:
            proprioception: (P,) one step's proprioception (angles first).
        Returns:
            (2 hands, 2 eyes, 3) [x, y, depth]: pixels (x right, y down, from the image's
            corner; outside [0, image_size) when out of the field of view) and the distance
            before the eye (m; <= 0 behind it, where x and y are NaN).
        """
        angles = np.asarray(proprioception, dtype=float)[: self.angles]
        positions, rotations = self.frames(angles)
        out = np.full((2, 2, 3), np.nan)
        half = self.image_size / 2.0
        for hand, geoms in enumerate(self.hands):
            centre = np.mean([positions[b] + rotations[b] @ pos for b, pos in geoms], axis=0)
            for eye, (body, pos, rotation, focal) in enumerate(self.eyes):
                camera = rotations[body] @ rotation
                v = camera.T @ (centre - (positions[body] + rotations[body] @ pos))
                depth = -v[2]  # a MuJoCo camera looks down its -z axis, y up
                out[hand, eye, 2] = depth
                if depth > 1e-6:
                    out[hand, eye, 0] = half + focal * v[0] / depth
                    out[hand, eye, 1] = half - focal * v[1] / depth
        return out
