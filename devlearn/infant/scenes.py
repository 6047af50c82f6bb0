"""The scenes: lying in a crib (self-touch), and sitting before toy blocks (hand regard) in two
versions, BabyBench's (head pitch held, arms hanging: the hand-regard default) and our first one."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

from dm_control import mjcf

from devlearn.infant.body import WORLD_CONTYPE, add_infant
from devlearn.infant.body_table import BODY_TABLE, MITTEN_RGBA, RIGHT_MITTEN_RGBA, SKIN_RGBA
from devlearn.infant.growth import GrownBody
from devlearn.timing import EPISODE_STEPS, PHYSICS_TIMESTEP  # noqa: F401 (re-exported)

SCENE_GROUP = 2  # geom group of everything that is not the infant (hidden in body-map pictures)

TOY_COLOURS = (
    (0.85, 0.15, 0.15, 1),
    (0.15, 0.65, 0.2, 1),
    (0.1, 0.72, 0.8, 1),
    (0.95, 0.85, 0.1, 1),
)
"""Red, green, cyan and yellow toys: hues far (>= 40 of OpenCV's 180) from the purple mittens
(hue about 138), so colour alone can tell a hand from a toy."""

NATURAL_TOY_COLOURS = (
    (0.85, 0.12, 0.1, 1),
    (0.1, 0.3, 0.8, 1),
    (0.95, 0.8, 0.1, 1),
    (0.76, 0.6, 0.42, 1),
)
"""Red, blue, yellow and natural wood: the usual colours of wooden baby blocks, chosen with no
regard to the hands. Red (OpenCV hue about 1), wood (about 15) and yellow (about 26) sit
around the bare skin's hue (about 12); wood is also close to it in saturation (0.45 against
0.31), so colour alone does not tell a hand from every toy."""


@dataclass(frozen=True)
class Appearance:
    """How the infant and its toys look (colours only; bodies and physics are the same).

    Attributes:
        hand_rgba: Colour of the hand and fingers bodies.
        toy_colours: Colours of the toy blocks (sitting) and of the mobile (crib), in order.
        right_hand_rgba: The right hand's colour when it differs from ``hand_rgba``.
    """

    hand_rgba: tuple[float, float, float, float]
    toy_colours: tuple[tuple[float, float, float, float], ...]
    right_hand_rgba: tuple[float, float, float, float] | None = None


APPEARANCES = {
    # Purple mittens, toys recoloured away from their hue: hands found by colour easily.
    "mittens": Appearance(MITTEN_RGBA, TOY_COLOURS),
    # Bare hands the colour of the body (as in MIMo), toys in the natural palette: the
    # paper's problem, hands told apart from arms, legs and toys only by how they move.
    "skin": Appearance(SKIN_RGBA, NATURAL_TOY_COLOURS),
    # Purple left mitten, magenta right one: which hand is in view shows in its colour (in
    # BabyBench's scene both hands rise into view at the same places, so position cannot tell).
    "two_colour_mittens": Appearance(MITTEN_RGBA, TOY_COLOURS, RIGHT_MITTEN_RGBA),
}
"""Appearances by name (``build_infant(..., appearance=NAME)``); ``mittens`` is the default."""


@dataclass(frozen=True)
class SceneSpec:
    """What differs between scenes.

    Attributes:
        name: "crib" or "sitting".
        actuated_groups: Joint groups with motors; every other joint is locked (held).
        held: Held angles (radians) of locked joints by full name; default 0.
        root_pos, root_quat: Pose of the fixed hip in the world.
        rest: Initial angles of actuated joints when not posed randomly (full names).
        overview: Third-person camera (pos, xyaxes) for ``render_view``.
        equality: Actuated joints held at an angle (radians) by equality constraints: their
            motors stay (the action size is unchanged) but cannot move them, as in BabyBench.
        settle_steps: Zero-action physics steps taken from ``rest`` when the infant is built;
            the settled state is the scene's initial state (BabyBench: 100). 0: ``rest`` as is.
    """

    name: str
    actuated_groups: frozenset[str]
    held: dict[str, float]
    root_pos: tuple[float, float, float]
    root_quat: tuple[float, float, float, float]
    rest: dict[str, float] = field(default_factory=dict)
    overview: tuple[tuple[float, ...], tuple[float, ...]] = ((0, 0, 1), (1, 0, 0, 0, 1, 0))
    equality: dict[str, float] = field(default_factory=dict)
    settle_steps: int = 0


_HALF = math.sqrt(0.5)
_Q = math.pi / 2
_WALLS = (
    ((2, 0, 1), (0, -_Q, 0)),
    ((-2, 0, 1), (0, _Q, 0)),
    ((0, 2, 1), (_Q, 0, 0)),
    ((0, -2, 1), (-_Q, 0, 0)),
)
_SITTING_LEGS = {
    f"{s}_{j}": a
    for s in ("left", "right")
    for j, a in (("hip_flexion", math.radians(90)), ("hip_abduction", 0.4), ("fingers", 0.3))
}

BABYBENCH_HEAD_PITCH = 0.4
"""Head pitch (rad, forward-down) that BabyBench's hand-regard scene holds by a constraint
(facts sec. 3b); its side tilt is held at 0, only the swivel moves."""
SETTLE_STEPS = 100
"""BabyBench: 100 zero-action physics steps from the scene's pose make the initial state."""

_SITTING = SceneSpec(
    "sitting",
    frozenset({"head", "arm", "wrist"}),
    _SITTING_LEGS,
    root_pos=(0.0, 0.0, 0.07),
    root_quat=(1.0, 0.0, 0.0, 0.0),
    rest={
        "head_tilt": 0.5,
        "left_elbow": 0.6,
        "right_elbow": 0.6,
        "left_shoulder_flexion": 0.4,
        "right_shoulder_flexion": 0.4,
    },
    overview=((0.75, -0.55, 0.55), (0.59, 0.81, 0.0, -0.35, 0.25, 0.9)),
)

SCENES = {
    # On its back, head towards +x: body x (front) -> world z, body z (up) -> world x, so the
    # body's left (+y) is world -y. The hip is welded to the mattress at its own radius.
    "crib": SceneSpec(
        "crib",
        frozenset({"trunk", "head", "arm", "wrist", "fingers", "leg"}),
        {},
        root_pos=(0.0, 0.0, 0.05),
        root_quat=(0.0, _HALF, 0.0, _HALF),
        rest={"left_shoulder_abduction": 0.15, "right_shoulder_abduction": 0.15},
        overview=((-0.55, -0.45, 0.75), (0.63, -0.77, 0.0, 0.45, 0.37, 0.81)),
    ),
    # Upright on the floor, legs straight forward in a V, trunk and legs held.
    "sitting": _SITTING,
    # BabyBench's hand-regard scene (facts sec. 3b), the hand_regard default: sitting as above,
    # but the head's pitch held at 0.4 rad and its side tilt at 0 by equality constraints (their
    # motors kept: 17 actions), only the swivel free, eyes locked, and the arms hanging at the
    # sides, hands beside the hips, out of both eyes' view; the state after 100 zero-action
    # steps is the initial state. Bringing a hand into view must be learned.
    "sitting_babybench": replace(
        _SITTING,
        name="sitting_babybench",
        rest={
            "head_tilt": BABYBENCH_HEAD_PITCH,
            "left_shoulder_abduction": 0.25,
            "right_shoulder_abduction": 0.25,
            # hands beside the hips, ~85 degrees off the eyes' axes (BabyBench: 80-86)
            "left_shoulder_flexion": 0.2,
            "right_shoulder_flexion": 0.2,
        },
        equality={"head_tilt": BABYBENCH_HEAD_PITCH, "head_tilt_side": 0.0},
        settle_steps=SETTLE_STEPS,
    ),
}
"""Scenes by name. ``sitting`` is the hand-regard scene of runs before issue #29 (head free,
hands raised before the eyes at rest); ``sitting_babybench`` is BabyBench's, the default."""

SITTING_SCENES = ("sitting", "sitting_babybench")
"""The scenes with the sitting body (17 actuators, toy blocks)."""


def _options(root: mjcf.RootElement) -> None:
    root.compiler.angle = "radian"
    root.option.timestep = PHYSICS_TIMESTEP
    root.option.integrator = "implicitfast"  # damping integrated implicitly: stable at 5 ms
    root.option.iterations = 20
    root.option.ls_iterations = 8
    root.default.geom.condim = 3
    root.default.geom.friction = (1.0, 0.005, 0.0002)
    # Fast software rendering: no multisampling, coarse built-in shapes, small shadow map.
    quality = root.visual.quality
    quality.offsamples = 0
    quality.numslices = 16
    quality.numstacks = 8
    quality.numquads = 1
    quality.shadowsize = 256
    glob = getattr(root.visual, "global")
    glob.offwidth, glob.offheight = 1280, 960
    root.visual.map.znear = 0.002
    root.visual.headlight.ambient = (0.35, 0.35, 0.35)
    root.visual.headlight.diffuse = (0.35, 0.35, 0.35)


def _props(root: mjcf.RootElement, scene: str, toy_colours: Sequence[Sequence[float]]) -> None:
    world = root.worldbody
    world.add(
        "light",
        name="sun",
        pos=(0, 0, 2.0),
        dir=(0, 0, -1),
        directional=True,
        diffuse=(0.4, 0.4, 0.4),
        castshadow=False,
    )
    if scene == "crib":
        _prop(world, "mattress", "plane", (0.6, 0.4, 0.05), (0.6, 0.75, 0.92, 1), solid=True)
        # Something to look at: a ceiling (a plane seen from below) and the crib's rails.
        _prop(
            world, "ceiling", "plane", (1.5, 1.5, 0.05), (0.95, 0.92, 0.8, 1),
            pos=(0, 0, 1.4), euler=(math.pi, 0, 0),
        )  # fmt: skip
        wood = (0.8, 0.62, 0.42, 1)
        for i, (x, y, sx, sy) in enumerate(
            ((0.6, 0, 0.02, 0.4), (-0.6, 0, 0.02, 0.4), (0, 0.4, 0.6, 0.02), (0, -0.4, 0.6, 0.02))
        ):
            _prop(world, f"rail_{i}", "box", (sx, sy, 0.15), wood, pos=(x, y, 0.15))
        # A mobile of coloured shapes hanging over the infant's face.
        for i, (x, y, rgba) in enumerate(zip((0.36, 0.28, 0.22), (0.08, -0.07, 0.03), toy_colours)):
            _prop(world, f"mobile_{i}", "sphere", (0.03,), rgba, pos=(x, y, 0.62))
    else:  # both sitting scenes
        _prop(world, "floor", "plane", (2.0, 2.0, 0.05), (0.72, 0.74, 0.78, 1), solid=True)
        # The room's walls: planes 2 m away, facing the infant.
        paint = (0.93, 0.9, 0.82, 1)
        for i, (pos, euler) in enumerate(_WALLS):
            _prop(world, f"wall_{i}", "plane", (2.0, 1.0, 0.05), paint, pos=pos, euler=euler)
        blocks = ((0.24, 0.05, 0.4), (0.3, -0.07, -0.3), (0.37, 0.02, 0.1), (0.21, -0.02, 0.8))
        for i, ((x, y, yaw), rgba) in enumerate(zip(blocks, toy_colours)):
            _prop(
                world, f"toy_{i}", "box", (0.02, 0.02, 0.02), rgba, solid=True,
                pos=(x, y, 0.02), euler=(0, 0, yaw),
            )  # fmt: skip


def _prop(
    world: mjcf.Element,
    name: str,
    shape: str,
    size: Sequence[float],
    rgba: Sequence[float],
    solid: bool = False,
    **placement: Sequence[float],
) -> None:
    """Add a geom of the scene (``SCENE_GROUP``) at ``placement`` (``pos``, ``euler``). A solid
    one (the mattress, the floor, the toys) collides with the infant; the rest are visual only
    (contype 0), so they cost no collision checks."""
    contact = (
        {"contype": WORLD_CONTYPE, "conaffinity": 1} if solid else {"contype": 0, "conaffinity": 0}
    )
    world.add(
        "geom",
        group=SCENE_GROUP,
        name=name,
        type=shape,
        size=size,
        rgba=rgba,
        **placement,
        **contact,
    )


def build_scene_model(
    scene: str,
    vestibular: bool = True,
    appearance: str = "mittens",
    body: GrownBody | None = None,
) -> tuple[mjcf.RootElement, list[str]]:
    """Build the MJCF model of a scene.

    Args:
        scene: A key of :data:`SCENES`.
        vestibular: Add the head's accelerometer and gyro.
        appearance: A key of :data:`APPEARANCES` (hand and toy colours).
        body: The infant at an age (:func:`devlearn.infant.growth.grown_body`); None: the
            default body. The hip is placed as high above the mattress or floor as the
            default's, times the ratio of their hip radii (in the crib: at its own radius).

    Returns:
        (root element, actuated joint names in actuator order).
    """
    if scene not in SCENES:
        raise ValueError(f"unknown scene '{scene}'; valid scenes: {', '.join(SCENES)}")
    if appearance not in APPEARANCES:
        raise ValueError(
            f"unknown appearance '{appearance}'; valid appearances: {', '.join(APPEARANCES)}"
        )
    spec = SCENES[scene]
    look = APPEARANCES[appearance]
    root = mjcf.RootElement(model=f"infant_{scene}")
    _options(root)
    _props(root, scene, look.toy_colours)
    pos, xyaxes = spec.overview
    root.worldbody.add("camera", name="overview", pos=pos, xyaxes=xyaxes, fovy=50)
    root_pos, table, density = spec.root_pos, BODY_TABLE, None
    if body is not None:
        table, density = body.table, body.density
        hip = body.table[0].geoms[0].size[0] / BODY_TABLE[0].geoms[0].size[0]
        root_pos = (root_pos[0], root_pos[1], root_pos[2] * hip)
    actuated = add_infant(
        root,
        root_pos=root_pos,
        root_quat=spec.root_quat,
        actuated_groups=set(spec.actuated_groups),
        held=spec.held,
        vestibular=vestibular,
        hand_rgba=look.hand_rgba,
        right_hand_rgba=look.right_hand_rgba,
        table=table,
        density=density,
    )
    for joint, angle in spec.equality.items():
        # joint1 = polycoef[0]: the angle held; the motor on it pushes against the constraint.
        root.equality.add("joint", name=f"hold_{joint}", joint1=joint, polycoef=(angle, 0, 0, 0, 0))
    return root, actuated
