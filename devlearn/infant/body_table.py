"""The infant's body as a readable table: parts, sizes, joints, torques (left side + midline)."""

from __future__ import annotations

import hashlib
import math
from dataclasses import astuple, dataclass

Vec3 = tuple[float, float, float]

SKIN_RGBA = (0.95, 0.78, 0.66, 1.0)
MITTEN_RGBA = (0.62, 0.38, 0.78, 1.0)
"""In the ``mittens`` appearance the hands (hand and fingers bodies) wear purple mittens: a
colour apart from the skin and from the toys, as an infant's mittens would be. In the ``skin``
appearance (``build_infant(..., appearance="skin")``) they are bare, ``SKIN_RGBA`` like the rest
of the body (as in MIMo). Nothing in devlearn tells a behaviour either colour: hand_regard
learns what its hands look like from motor babbling."""
RIGHT_MITTEN_RGBA = (0.88, 0.22, 0.62, 1.0)
"""The right mitten's colour in the ``two_colour_mittens`` appearance: magenta (OpenCV hue
about 162), 24 hue steps from the left's purple (138) and 18 from the red toy (0), so that a
detector can learn which hand it sees from its colour."""
MITTEN_BODIES = ("hand", "fingers")
"""Bodies coloured by the appearance's hand colour."""
EYE_RGBA = (0.15, 0.10, 0.08, 1.0)


@dataclass(frozen=True)
class JointSpec:
    """One hinge joint, in its body's frame (left side; the right side is mirrored).

    Attributes:
        name: Side-free name ("elbow"); paired bodies get "left_"/"right_" prefixes.
        axis: Rotation axis (positive = the named movement, e.g. flexion).
        range: Limits in radians.
        max_torque: Motor torque at action 1 (N m), from the facts file.
        group: Actuator group: trunk, head, eyes, arm, wrist, fingers, leg, foot.
        stiffness, damping, armature, frictionloss: Passive spring-damper properties.
    """

    name: str
    axis: Vec3
    range: tuple[float, float]
    max_torque: float
    group: str
    stiffness: float
    damping: float
    armature: float
    frictionloss: float


@dataclass(frozen=True)
class GeomSpec:
    """One collision (and visual) geom: sphere (r), capsule (r; fromto) or box (half sizes)."""

    name: str
    kind: str
    size: tuple[float, ...]
    pos: Vec3 = (0.0, 0.0, 0.0)
    fromto: tuple[float, float, float, float, float, float] | None = None


@dataclass(frozen=True)
class BodySpec:
    """One rigid body of the infant.

    Attributes:
        name: Side-free name; paired bodies exist as "left_<name>" and "right_<name>".
        parent: Parent body's side-free name ("" for the root).
        pos: Origin in the parent's frame (standing pose: x forward, y left, z up).
        joints: Hinge joints at the body's origin, outermost first.
        geoms: Collision geoms.
        spacing: Tactile sensor spacing in metres (facts file, sec. 2); None: no skin.
        paired: True for left/right bodies (defined here for the left side, y > 0).
        collides: False for the eyes (they never touch anything).
        camera: True for the eyes: a camera looking forward along +x.
        camera_offset: How far in front of the body's origin the camera sits (m): just
            outside the eye's surface.
    """

    name: str
    parent: str
    pos: Vec3
    joints: tuple[JointSpec, ...]
    geoms: tuple[GeomSpec, ...]
    spacing: float | None
    paired: bool = False
    collides: bool = True
    camera: bool = False
    camera_offset: float = 0.0115


# Passive properties per joint group: (stiffness N m/rad, damping N m s/rad, armature kg m^2,
# frictionloss N m). Stiff enough to hold a pose against the mattress, damped for dt = 5 ms.
PASSIVE = {
    "trunk": (2.0, 0.5, 0.05, 0.05),
    "head": (0.5, 0.1, 0.01, 0.01),
    "eyes": (0.01, 0.001, 1e-4, 0.0),
    "arm": (0.2, 0.1, 0.01, 0.01),
    "wrist": (0.05, 0.03, 0.003, 0.005),
    "fingers": (0.02, 0.01, 0.001, 0.002),
    "leg": (0.5, 0.2, 0.02, 0.02),
    "foot": (0.2, 0.05, 0.005, 0.005),
}


def _j(name: str, axis: Vec3, lo_deg: float, hi_deg: float, torque: float, group: str) -> JointSpec:
    return JointSpec(
        name, axis, (math.radians(lo_deg), math.radians(hi_deg)), torque, group, *PASSIVE[group]
    )


def _capsule_y(name: str, half: float, r: float, x: float = 0.0, z: float = 0.0) -> GeomSpec:
    """A capsule across the body (along y), centred at (x, 0, z)."""
    return GeomSpec(name, "capsule", (r,), fromto=(x, -half, z, x, half, z))


def _capsule_down(name: str, length: float, r: float, top: float = 0.0) -> GeomSpec:
    """A capsule hanging down the limb (along -z) from z = -top."""
    return GeomSpec(name, "capsule", (r,), fromto=(0.0, 0.0, -top, 0.0, 0.0, -top - length))


X, Y, Z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)
NX, NY, NZ = (-1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, -1.0)

# An 18-month-old, 77.8 cm tall (facts sec. 1): sole at z = -0.355, crown at z = 0.4235 in the
# hip frame; arm 31.8 cm shoulder to fingertip, leg 32.5 cm hip joint to sole, head r 7.35 cm.
# Torques in N m are the facts file's; ranges are infant-like, in degrees.
# fmt: off
BODY_TABLE: tuple[BodySpec, ...] = (
    BodySpec("hip", "", (0.0, 0.0, 0.0), (), (_capsule_y("hip", 0.04, 0.05),), 0.025),
    BodySpec("lower_body", "hip", (0.0, 0.0, 0.05), (
        _j("trunk_bend", Y, -25, 60, 10.58, "trunk"),
        _j("trunk_lean", X, -30, 30, 7.25, "trunk"),
    ), (_capsule_y("lower_body", 0.035, 0.048, z=0.04),), 0.025),
    BodySpec("upper_body", "lower_body", (0.0, 0.0, 0.06), (
        _j("trunk_twist", Z, -45, 45, 3.63, "trunk"),
    ), (
        _capsule_y("waist", 0.035, 0.05, z=0.02),
        _capsule_y("ribs", 0.04, 0.053, z=0.072),
        _capsule_y("shoulders", 0.055, 0.04, z=0.12),
    ), 0.030),
    BodySpec("head", "upper_body", (0.0, 0.0, 0.155), (
        _j("head_swivel", Z, -75, 75, 1.8, "head"),
        _j("head_tilt", Y, -40, 60, 3.3, "head"),
        _j("head_tilt_side", X, -40, 40, 1.8, "head"),
    ), (GeomSpec("head", "sphere", (0.0735,), pos=(0.02, 0.0, 0.085)),), 0.013),
    BodySpec("eye", "head", (0.078, 0.027, 0.097), (
        _j("eye_horizontal", Z, -30, 30, 0.0054, "eyes"),
        _j("eye_vertical", Y, -30, 30, 0.0054, "eyes"),
        _j("eye_torsional", X, -10, 10, 0.0037, "eyes"),
    ), (GeomSpec("eye", "sphere", (0.01125,)),), None, paired=True, collides=False,
        camera=True),
    BodySpec("upper_arm", "upper_body", (0.0, 0.105, 0.115), (
        _j("shoulder_flexion", NY, -40, 160, 1.8, "arm"),
        _j("shoulder_abduction", X, -45, 150, 4.0, "arm"),
        _j("shoulder_rotation", NZ, -60, 90, 2.5, "arm"),
    ), (_capsule_down("upper_arm", 0.105, 0.026),), 0.024, paired=True),
    BodySpec("lower_arm", "upper_arm", (0.0, 0.0, -0.125), (
        _j("elbow", NY, 0, 145, 3.6, "arm"),
    ), (_capsule_down("lower_arm", 0.085, 0.023),), 0.024, paired=True),
    BodySpec("hand", "lower_arm", (0.0, 0.0, -0.105), (
        _j("wrist_rotation", NZ, -90, 90, 0.7, "wrist"),
        _j("wrist_flexion", NY, -70, 80, 1.24, "wrist"),
        _j("wrist_ulnar", NX, -25, 35, 0.95, "wrist"),
    ), (GeomSpec("hand", "box", (0.01, 0.022, 0.025), pos=(0.0, 0.0, -0.025)),), 0.007,
        paired=True),
    BodySpec("fingers", "hand", (0.0, 0.0, -0.05), (
        _j("fingers", NY, -10, 110, 0.69, "fingers"),
    ), (GeomSpec("fingers", "box", (0.0075, 0.022, 0.019), pos=(0.0, 0.0, -0.019)),), 0.002,
        paired=True),
    BodySpec("upper_leg", "hip", (0.0, 0.05, -0.03), (
        _j("hip_flexion", NY, -20, 130, 8.0, "leg"),
        _j("hip_abduction", X, -20, 60, 6.24, "leg"),
        _j("hip_rotation", NZ, -45, 45, 3.54, "leg"),
    ), (_capsule_down("upper_leg", 0.11, 0.037, top=0.01),), 0.027, paired=True),
    BodySpec("lower_leg", "upper_leg", (0.0, 0.0, -0.14), (
        _j("knee", Y, 0, 145, 10.0, "leg"),
    ), (_capsule_down("lower_leg", 0.115, 0.033),), 0.038, paired=True),
    BodySpec("foot", "lower_leg", (0.0, 0.0, -0.14), (
        _j("ankle_flexion", NY, -50, 30, 3.78, "foot"),
        _j("foot_inversion", X, -25, 35, 1.16, "foot"),
        _j("foot_rotation", Z, -30, 30, 1.2, "foot"),
    ), (GeomSpec("foot", "box", (0.045, 0.025, 0.018), pos=(0.02, 0.0, -0.027)),), 0.015,
        paired=True),
    BodySpec("toes", "foot", (0.065, 0.0, -0.035), (
        _j("toes", NY, -30, 60, 0.33, "foot"),
    ), (GeomSpec("toes", "box", (0.012, 0.024, 0.009), pos=(0.012, 0.0, 0.0)),), 0.010,
        paired=True),
)
# fmt: on

# Body pairs that overlap at a joint without being parent and child (MuJoCo already filters
# parent-child contacts): excluding them keeps the contact count low.
EXCLUDED_PAIRS: tuple[tuple[str, str], ...] = (
    ("hip", "upper_body"),
    ("lower_body", "upper_leg"),
    ("lower_arm", "fingers"),
    ("lower_leg", "toes"),
)

SIDES = ("left", "right")


def spec_by_name(name: str) -> BodySpec:
    """The table row of a side-free body name ("hand", "head")."""
    for spec in BODY_TABLE:
        if spec.name == name:
            return spec
    raise KeyError(f"unknown body part '{name}'; known: {[s.name for s in BODY_TABLE]}")


def table_hash() -> str:
    """A short hash of the whole table (keys caches of anything derived from it)."""
    text = repr([astuple(spec) for spec in BODY_TABLE]) + repr(EXCLUDED_PAIRS)
    return hashlib.sha256(text.encode()).hexdigest()[:16]
