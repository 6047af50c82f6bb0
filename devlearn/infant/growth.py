"""A body that grows: the body table rebuilt at any age from birth to 24 months.

The default body (:data:`~devlearn.infant.body_table.BODY_TABLE`, MIMo v1's "18-month-old") is
scaled part by part, each axis of each part by the growth of the measurement it stands for
(:data:`PART_GROWTH`), relative to :data:`REFERENCE_AGE`, the age whose WHO median length the
default body has:

- the head (and eyes) by the WHO median head circumference;
- limb segments, hands and feet by AnthroKids' lengths, circumferences and breadths
  (:data:`~devlearn.infant.growth_data.ANTHROKIDS_CURVES`, MIMo v2's growth data);
- the trunk's length by the WHO median length, its breadth and depth by AnthroKids' hip
  breadth.

Then two calibrations make the whole body the WHO median's: one factor on every length but the
head's, so that the crown-heel length (:func:`crown_heel_length`) is the WHO median length, and
one on every girth and breadth but the head's, so that the mass at :data:`DENSITY` is the WHO
median weight (MuJoCo computes every body's mass and inertia from its geoms at that density;
docs/growth.md has the figures). Motor torques and the joints' passive spring-damper
scale with the volume of the body each joint moves (MIMo v2's rule: strength follows muscle
volume). The skin keeps its sensors: each one moves with its geom's surface
(:func:`devlearn.infant.skin_layout.grown_layout`), so the 68 regions hold as many sensors at
every age and their spacing scales with the body.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import partial
from typing import Any, ClassVar, cast

from devlearn.ages import check_age
from devlearn.infant.body_table import BODY_TABLE, BodySpec, GeomSpec, JointSpec, Vec3
from devlearn.infant.growth_data import (
    WHO_HEAD_CM,
    WHO_LENGTH_CM,
    WHO_WEIGHT_KG,
    anthrokids_size,
    who_age_of,
    who_median,
)

DEFAULT_BODY_NAME = "MIMo v1's 18-month-old"
"""What the default body (``infant.age_months`` unset) is: 77.8 cm and 10.96 kg, the WHO boys'
median length at 13.8 months and median weight at 18.1 months, so no single age fits it
within 3%; it stays exactly as every published run was trained."""


@dataclass(frozen=True)
class PartGrowth:
    """Which measurement scales each axis of one body part (in the body's frame).

    Attributes:
        x, y, z: Measures scaling the part's positions and box sizes along its axes (x
            forward, y left, z up in the standing pose).
        radius: Measure scaling its spheres' and capsules' radii.
    """

    x: str
    y: str
    z: str
    radius: str


_TRUNK = PartGrowth("hip_breadth", "hip_breadth", "trunk_length", "hip_breadth")
_HEAD = PartGrowth("head", "head", "head", "head")
_FOOT = PartGrowth("foot_length", "foot_breadth", "foot_height", "foot_breadth")

PART_GROWTH: dict[str, PartGrowth] = {
    "hip": _TRUNK,
    "lower_body": _TRUNK,
    "upper_body": _TRUNK,
    "head": _HEAD,
    "eye": _HEAD,
    "upper_arm": PartGrowth(
        "upper_arm_circumference",
        "upper_arm_circumference",
        "shoulder_elbow_length",
        "upper_arm_circumference",
    ),
    "lower_arm": PartGrowth(
        "forearm_circumference",
        "forearm_circumference",
        "forearm_length",
        "forearm_circumference",
    ),
    "hand": PartGrowth("hand_thickness", "hand_breadth", "hand_length", "hand_breadth"),
    "fingers": PartGrowth("middle_finger_diameter", "hand_breadth", "hand_length", "hand_breadth"),
    "upper_leg": PartGrowth(
        "mid_thigh_circumference",
        "mid_thigh_circumference",
        "rump_knee_length",
        "mid_thigh_circumference",
    ),
    "lower_leg": PartGrowth(
        "calf_circumference", "calf_circumference", "knee_sole_length", "calf_circumference"
    ),
    "foot": _FOOT,
    "toes": _FOOT,
}
"""How each part of :data:`~devlearn.infant.body_table.BODY_TABLE` grows. A child body's
position is in its parent's frame and scales with the parent's axes; a capsule's length with
the axis it lies along."""

LENGTHS = frozenset(
    {
        "trunk_length",
        "shoulder_elbow_length",
        "forearm_length",
        "hand_length",
        "rump_knee_length",
        "knee_sole_length",
        "foot_length",
    }
)
"""Measures that the length calibration scales (every length but the head's)."""


def _measure(name: str, age: float) -> float:
    """A measurement at ``age`` in its own unit (only ratios between ages are used)."""
    if name == "head":
        return who_median(WHO_HEAD_CM, age)
    if name == "trunk_length":
        return who_median(WHO_LENGTH_CM, age)
    if name == "forearm_length":
        return _measure("elbow_hand_length", age) - _measure("hand_length", age)
    if name == "hand_thickness":  # no measurement: the mean of the hand's length and breadth
        return 0.5 * (_measure("hand_length", age) + _measure("hand_breadth", age))
    if name == "foot_height":  # likewise for the foot
        return 0.5 * (_measure("foot_length", age) + _measure("foot_breadth", age))
    return anthrokids_size(name, age)


# -- volumes and areas ---------------------------------------------------------------------


def geom_volume(geom: GeomSpec) -> float:
    """Volume (m^3) of a geom, as MuJoCo computes it for the mass."""
    if geom.kind == "sphere":
        return 4.0 / 3.0 * math.pi * geom.size[0] ** 3
    if geom.kind == "capsule":
        r = geom.size[0]
        assert geom.fromto is not None
        length = math.dist(geom.fromto[:3], geom.fromto[3:])
        return math.pi * r * r * length + 4.0 / 3.0 * math.pi * r**3
    if geom.kind == "box":
        return 8.0 * geom.size[0] * geom.size[1] * geom.size[2]
    raise ValueError(f"no volume for geom kind '{geom.kind}'; use sphere, capsule or box")


def geom_area(geom: GeomSpec) -> float:
    """Surface area (m^2) of a geom (what its skin covers)."""
    if geom.kind == "sphere":
        return 4.0 * math.pi * geom.size[0] ** 2
    if geom.kind == "capsule":
        r = geom.size[0]
        assert geom.fromto is not None
        return 2.0 * math.pi * r * math.dist(geom.fromto[:3], geom.fromto[3:]) + 4 * math.pi * r * r
    if geom.kind == "box":
        a, b, c = geom.size[:3]
        return 8.0 * (a * b + b * c + c * a)
    raise ValueError(f"no area for geom kind '{geom.kind}'; use sphere, capsule or box")


def _body_volume(spec: BodySpec) -> float:
    return sum(geom_volume(g) for g in spec.geoms)


def table_volume(table: tuple[BodySpec, ...]) -> float:
    """Volume (m^3) of the whole infant (paired bodies twice; the eyes included)."""
    return sum((2 if s.paired else 1) * _body_volume(s) for s in table)


# -- the default body's own measures --------------------------------------------------------


def _world_pos(table: tuple[BodySpec, ...], name: str) -> Vec3:
    """A body's origin in the hip's frame in the standing pose (every joint at 0)."""
    spec = next(s for s in table if s.name == name)
    if not spec.parent:
        return spec.pos
    px, py, pz = _world_pos(table, spec.parent)
    return (px + spec.pos[0], py + spec.pos[1], pz + spec.pos[2])


def _geom_extent_z(geom: GeomSpec) -> tuple[float, float]:
    """Lowest and highest z of a geom in its body's frame."""
    if geom.kind == "box":
        return geom.pos[2] - geom.size[2], geom.pos[2] + geom.size[2]
    r = geom.size[0]
    if geom.fromto is not None:
        z1, z2 = geom.fromto[2], geom.fromto[5]
        return min(z1, z2) - r, max(z1, z2) + r
    return geom.pos[2] - r, geom.pos[2] + r


def standing_extent(table: tuple[BodySpec, ...] = BODY_TABLE) -> tuple[float, float]:
    """The lowest sole and the crown (m) along the body's long axis, in the hip's frame,
    standing with every joint at 0 (legs straight)."""
    top, bottom = -math.inf, math.inf
    for spec in table:
        if not spec.collides:
            continue
        z0 = _world_pos(table, spec.name)[2]
        for geom in spec.geoms:
            lo, hi = _geom_extent_z(geom)
            top, bottom = max(top, z0 + hi), min(bottom, z0 + lo)
    return bottom, top


def crown_heel_length(table: tuple[BodySpec, ...] = BODY_TABLE) -> float:
    """Crown-heel length (m) of a body table: the top of the head to the lowest sole, standing
    with every joint at 0 (legs straight), as a recumbent length is measured lying
    (:func:`standing_extent`)."""
    bottom, top = standing_extent(table)
    return top - bottom


REFERENCE_AGE = who_age_of(WHO_LENGTH_CM, 100.0 * crown_heel_length(BODY_TABLE))
"""The age (months, about 13.8) at which the WHO boys' median length is the default body's
crown-heel length: every growth ratio is taken against this age, so the growth model's body
at this age has the default body's shape."""

DENSITY = who_median(WHO_WEIGHT_KG, REFERENCE_AGE) / table_volume(BODY_TABLE)
"""Density (kg/m^3, about 917) of every geom of a grown body: the one at which the default
body's shape weighs the WHO median at :data:`REFERENCE_AGE` (the default body, at MuJoCo's
1000, is 9% heavier: plump for its length)."""


# -- growing the table --------------------------------------------------------------------


def _scaled(v: tuple[float, ...], s: Vec3) -> tuple[float, ...]:
    """Scale 3-vectors (also 6-vectors like fromto) per axis."""
    return tuple(x * s[i % 3] for i, x in enumerate(v))


def _grow_geom(geom: GeomSpec, axes: Vec3, radius: float) -> GeomSpec:
    pos = cast(Vec3, _scaled(geom.pos, axes))
    if geom.kind == "box":
        return replace(geom, size=_scaled(geom.size, axes), pos=pos)
    fromto = None if geom.fromto is None else _scaled(geom.fromto, axes)
    size = (geom.size[0] * radius, *geom.size[1:])
    return replace(geom, size=size, pos=pos, fromto=cast(Any, fromto))


def _grow_joint(joint: JointSpec, strength: float) -> JointSpec:
    """Motor and passive spring-damper scaled alike: their balance stays the same at any age."""
    return replace(
        joint,
        max_torque=joint.max_torque * strength,
        stiffness=joint.stiffness * strength,
        damping=joint.damping * strength,
        armature=joint.armature * strength,
        frictionloss=joint.frictionloss * strength,
    )


def _grow_table(age: float, length_factor: float, girth_factor: float) -> tuple[BodySpec, ...]:
    """The table at ``age``, every length but the head's also times ``length_factor`` and
    every other measure but the head's times ``girth_factor`` (the two calibrations)."""

    def ratio(measure: str) -> float:
        r = _measure(measure, age) / _measure(measure, REFERENCE_AGE)
        if measure == "head":
            return r
        return r * (length_factor if measure in LENGTHS else girth_factor)

    axes: dict[str, Vec3] = {}
    radii: dict[str, float] = {}
    for spec in BODY_TABLE:
        growth = PART_GROWTH[spec.name]
        axes[spec.name] = (ratio(growth.x), ratio(growth.y), ratio(growth.z))
        radii[spec.name] = ratio(growth.radius)
    grown = []
    for spec in BODY_TABLE:
        own = axes[spec.name]
        geoms = tuple(_grow_geom(g, own, radii[spec.name]) for g in spec.geoms)
        pos = cast(Vec3, _scaled(spec.pos, axes[spec.parent])) if spec.parent else spec.pos
        strength = sum(geom_volume(g) for g in geoms) / _body_volume(spec)
        area = sum(geom_area(g) for g in geoms) / sum(geom_area(g) for g in spec.geoms)
        grown.append(
            replace(
                spec,
                pos=pos,
                geoms=geoms,
                joints=tuple(_grow_joint(j, strength) for j in spec.joints),
                spacing=None if spec.spacing is None else spec.spacing * math.sqrt(area),
                camera_offset=spec.camera_offset * radii[spec.name],
            )
        )
    return tuple(grown)


def _solve(increasing: Callable[[float], float], target: float, start: float) -> float:
    """The x near ``start`` where a smooth increasing function reaches ``target`` (secant
    steps; relative error below 1e-12)."""
    x0, x1 = start, start * 1.01
    f0, f1 = increasing(x0) - target, increasing(x1) - target
    for _ in range(50):
        if abs(f1) <= 1e-12 * abs(target) or f1 == f0:
            break
        x0, x1, f0 = x1, x1 - f1 * (x1 - x0) / (f1 - f0), f1
        f1 = increasing(x1) - target
    return x1


def _length_with_girth(age: float, girth_factor: float, length_factor: float) -> float:
    return crown_heel_length(_grow_table(age, length_factor, girth_factor))


def _volume_with_length(age: float, length_factor: float, girth_factor: float) -> float:
    return table_volume(_grow_table(age, length_factor, girth_factor))


@dataclass(frozen=True)
class GrownBody:
    """The body at one age: what :func:`~devlearn.infant.body.add_infant` builds.

    Attributes:
        age_months: The age.
        table: The body table at that age (the default's parts, joints and geoms, resized).
        length_factor: The length calibration (1: the growth curves' lengths alone).
        girth_factor: The girth calibration (1: the growth curves' girths alone).
    """

    age_months: float
    table: tuple[BodySpec, ...]
    length_factor: float
    girth_factor: float

    density: ClassVar[float] = DENSITY

    @property
    def length(self) -> float:
        """Crown-heel length (m)."""
        return crown_heel_length(self.table)

    @property
    def mass(self) -> float:
        """Mass (kg) MuJoCo gives the body (its geoms' volume at :data:`DENSITY`)."""
        return DENSITY * table_volume(self.table)


_GROWN: dict[float, GrownBody] = {}


def grown_body(age_months: float) -> GrownBody:
    """The body at ``age_months`` (0 to 24), calibrated to the WHO medians (cached per age).

    Two factors, found together: one on every length but the head's, so that the crown-heel
    length is the WHO median length, and one on every girth and breadth but the head's, so that
    the mass at :data:`DENSITY` is the WHO median weight. From 3 months on both stay within
    3% of 1 (the growth curves alone nearly agree with WHO); near birth they correct the
    curves' extrapolation.

    Raises:
        ValueError: The age is outside :data:`~devlearn.ages.AGE_RANGE`.
    """
    age = check_age(age_months)
    if age in _GROWN:
        return _GROWN[age]
    length = who_median(WHO_LENGTH_CM, age) / 100.0
    volume = who_median(WHO_WEIGHT_KG, age) / DENSITY
    k = c = 1.0
    for _ in range(4):  # the foot's height mixes both: a few rounds settle them together
        k = _solve(partial(_length_with_girth, age, c), length, k)
        c = _solve(partial(_volume_with_length, age, k), volume, c)
    body = GrownBody(age, _grow_table(age, k, c), k, c)
    if len(_GROWN) > 64:  # a growing run builds many ages: keep the cache small
        _GROWN.clear()
    _GROWN[age] = body
    return body
