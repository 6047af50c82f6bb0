"""The Infant: a scene's physics plus its senses, cached until the next step or reset."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import mujoco
import numpy as np
from dm_control import mjcf

from devlearn.ages import check_age
from devlearn.infant import contacts, starts, vision
from devlearn.infant.body_table import BODY_TABLE
from devlearn.infant.growth import grown_body
from devlearn.infant.regions import NUM_PARTS, NUM_REGIONS, RegionTable, region_table
from devlearn.infant.scenes import (
    APPEARANCES,
    EPISODE_STEPS,
    PHYSICS_TIMESTEP,
    SCENES,
    build_scene_model,
)
from devlearn.infant.senses import Proprioception, vestibular
from devlearn.infant.skin import Skin
from devlearn.infant.skin_layout import grown_layout

SENSES = ("touch", "proprioception", "vestibular", "eyes")
ACTUATOR_GROUPS = ("left_arm", "right_arm", "head", "trunk", "legs")


class SenseNotEnabledError(RuntimeError):
    """A sense was asked for that the infant was built without."""


def _group_of(joint: str) -> str:
    side, _, rest = joint.partition("_")
    for spec in BODY_TABLE:
        for j in spec.joints:
            if joint == j.name or (spec.paired and rest == j.name):
                if j.group in ("arm", "wrist", "fingers"):
                    return f"{side}_arm"
                return {"leg": "legs", "foot": "legs"}.get(j.group, j.group)
    raise KeyError(joint)


class Infant:
    """The simulated infant in one scene (see docs/architecture.md, "The infant"): MIMo v1's
    18-month-old, or the body at ``age_months`` (:mod:`devlearn.infant.growth`).

    Build with :func:`build_infant` (this class's public name). Senses are computed on first
    request after a ``step`` or ``reset`` and cached; returned arrays are read-only.
    """

    physics_timestep = PHYSICS_TIMESTEP
    control_timestep = PHYSICS_TIMESTEP  # one physics step per control step
    episode_steps = EPISODE_STEPS

    def __init__(
        self,
        scene: str,
        *,
        senses: Sequence[str] = SENSES,
        eye_size: int = 64,
        appearance: str = "mittens",
        start: str = "rest",
        compiled: bool = True,
        age_months: float | None = None,
    ) -> None:
        """Build the infant in a scene, reset to its rest pose.

        Args:
            scene: "crib" (lying, pelvis fixed, 30 actuators), "sitting_babybench" (BabyBench's
                hand-regard scene: trunk and legs held, head pitch and side tilt held by
                constraints, arms hanging; 17 actuators, toy blocks in front) or "sitting" (the
                same body with the head free and the hands raised at rest).
            senses: Any of "touch", "proprioception", "vestibular", "eyes".
            eye_size: Eye image height and width (pixels).
            appearance: "mittens" (purple mittens, toys coloured away from them) or "skin" (bare
                hands the body's colour, toys in the natural palette); see
                :data:`devlearn.infant.scenes.APPEARANCES`. Colours only: physics is the same.
            start: How episodes start unless ``reset`` is told (:data:`~.starts.STARTS`):
                ``rest``, ``babybench`` or ``random``.
            compiled: Touch and proprioception through the compiled routines
                (:mod:`devlearn.infant.kernels`, numba, loaded on first use); False: their
                numpy references, the same numbers, slower per step but with no compilation or
                numba import (what describing an infant needs).
            age_months: Build the body at this age, 0 to 24 months, from growth curves
                (:func:`devlearn.infant.growth.grown_body`: WHO median length and weight, body
                proportions that change with age, torques, and the same skin sensors spread over
                it); None: the default body, MIMo v1's 18-month-old (77.8 cm, 10.96 kg).
        """
        unknown = sorted(set(senses) - set(SENSES))
        if unknown:
            raise ValueError(f"unknown sense(s) {unknown}; valid senses: {', '.join(SENSES)}")
        if scene not in SCENES:
            raise ValueError(f"unknown scene '{scene}'; valid scenes: {', '.join(SCENES)}")
        if appearance not in APPEARANCES:
            raise ValueError(
                f"unknown appearance '{appearance}'; valid appearances: {', '.join(APPEARANCES)}"
            )
        if start not in starts.STARTS:
            raise ValueError(f"unknown start '{start}'; valid starts: {', '.join(starts.STARTS)}")
        self.scene = scene
        self.start = start
        """How episodes start when ``reset`` is not told (:data:`~.starts.STARTS`); settable."""
        self.senses = tuple(senses)
        self.eye_size = int(eye_size)
        self.appearance = appearance
        self.age_months = None if age_months is None else check_age(age_months)
        """The body's age (months), or None: the default body
        (:data:`~devlearn.infant.growth.DEFAULT_BODY_NAME`)."""
        body = None if self.age_months is None else grown_body(self.age_months)
        root, self.actuator_names = build_scene_model(
            scene, vestibular="vestibular" in senses, appearance=appearance, body=body
        )
        self.mjcf_model = root
        self.physics = mjcf.Physics.from_mjcf_model(root)
        self.model: mujoco.MjModel = self.physics.model.ptr
        self.data: mujoco.MjData = self.physics.data.ptr
        self.action_dim = len(self.actuator_names)
        groups = [_group_of(j) for j in self.actuator_names]
        self.actuator_groups = {
            g: np.array([i for i, x in enumerate(groups) if x == g], dtype=np.int64)
            for g in ACTUATOR_GROUPS
        }
        self.skin = _shared_skin(self.model, scene, self.age_months)
        self.regions: RegionTable = region_table()
        self._contacts = contacts.ContactReader(self.model, self.skin, compiled=compiled)
        self.hand_of_body = np.full(self.model.nbody, -1, dtype=np.int64)
        for h, side in enumerate(("left", "right")):
            for part in ("hand", "fingers"):
                self.hand_of_body[self.model.body(f"{side}_{part}").id] = h
        self.hand_labels = dict(vision.HAND_LABELS)
        self._proprio = Proprioception(self.model, self.actuator_names, compiled=compiled)
        joints = [self.model.joint(j) for j in self.actuator_names]
        self._qpos_index = np.array([j.qposadr[0] for j in joints])
        self._ranges = np.array([j.range for j in joints])
        spec = SCENES[scene]
        self._rest = np.array([spec.rest.get(j, 0.0) for j in self.actuator_names])
        # Joints held by equality constraints keep their angle in random poses too.
        for i, name in enumerate(self.actuator_names):
            if name in spec.equality:
                self._ranges[i] = spec.equality[name]
        self._toys = np.array(
            [g for g in range(self.model.ngeom) if self.model.geom(g).name.startswith("toy_")],
            dtype=np.int64,
        )
        self._toy_pose = (
            self.model.geom_pos[self._toys].copy(),
            self.model.geom_quat[self._toys].copy(),
        )
        self._gl: dict[str, Any] = {"eyes": None, "views": {}}  # renderers, made on first use
        self._cache: dict[str, Any] = {}
        self.steps = 0
        self._initial: tuple[np.ndarray, np.ndarray] | None = None
        if spec.settle_steps:
            # BabyBench: the state after settling from the scene's pose is every episode's.
            self._reset_to_rest()
            for _ in range(spec.settle_steps):
                mujoco.mj_step(self.model, self.data)
            self._initial = (self.data.qpos.copy(), self.data.qvel.copy())
        self.reset(np.random.default_rng(0), start="rest")

    # -- simulation -------------------------------------------------------------------------
    def reset(
        self, rng: np.random.Generator, random_pose: bool = False, start: str | None = None
    ) -> None:
        """Start an episode (:data:`~devlearn.infant.starts.STARTS`).

        ``rest``: the scene's initial state (its rest pose, settled for scenes with
        ``settle_steps``). ``babybench``: that state, then 10 physics steps of uniform-random
        actions drawn from ``rng``. ``random``: joint angles uniform within their ranges (joints
        held by equality constraints keep their angle) and, in a scene with toy blocks, the
        toys placed uniformly in :data:`~devlearn.infant.starts.TOY_AREA` with a random yaw
        (toys first, so the pose's penetration check sees them); otherwise the toys return to
        their places.

        Args:
            rng: Draws random poses and kicks.
            random_pose: Start ``random`` (what the core's ``random_pose`` stage option asks).
            start: One of the starts; default: ``random`` if ``random_pose``, else
                :attr:`start`.
        """
        start = "random" if random_pose else (start or self.start)
        if start not in starts.STARTS:
            raise ValueError(f"unknown start '{start}'; valid starts: {', '.join(starts.STARTS)}")
        starts.place_toys(
            self.model, self._toys, self._toy_pose, rng if start == "random" else None
        )
        if start == "random":
            mujoco.mj_resetData(self.model, self.data)
            starts.random_pose(self.model, self.data, self._qpos_index, self._ranges, rng)
        else:
            self._reset_to_rest()
            if start == "babybench":
                starts.kick(self.model, self.data, rng, starts.KICK_STEPS)
        self._cache.clear()
        self.steps = 0

    def continue_from(self, other: Infant) -> None:
        """Take over ``other``'s physical state: joint angles, velocities, controls, time and
        step count (``other`` is this scene's infant at another age: the same joints), so that
        a body rebuilt at a new age carries on its episode where the old one was."""
        if other.model.nq != self.model.nq or other.scene != self.scene:
            raise ValueError(
                f"cannot continue a {other.scene} infant ({other.model.nq} joint coordinates) "
                f"as a {self.scene} one ({self.model.nq})"
            )
        self.data.qpos[:] = other.data.qpos
        self.data.qvel[:] = other.data.qvel
        self.data.ctrl[:] = other.data.ctrl
        self.data.time = other.data.time
        mujoco.mj_forward(self.model, self.data)
        self.start = other.start
        self.steps = other.steps
        self._cache.clear()

    def _reset_to_rest(self) -> None:
        """The scene's initial state: its settled state if it has one, else the rest pose."""
        mujoco.mj_resetData(self.model, self.data)
        if self._initial is None:
            self.data.qpos[self._qpos_index] = self._rest
        else:
            self.data.qpos[:], self.data.qvel[:] = self._initial
        mujoco.mj_forward(self.model, self.data)

    def step(self, action: np.ndarray) -> None:
        """Apply ``action`` (action_dim,) in [-1, 1] (clipped): torque = max_torque * action."""
        action = np.asarray(action, dtype=np.float64)
        if action.shape != (self.action_dim,):
            raise ValueError(f"action has shape {action.shape}; expected ({self.action_dim},)")
        if not np.isfinite(action).all():
            raise ValueError("action contains NaN or inf")
        np.minimum(np.maximum(action, -1.0), 1.0, out=self.data.ctrl)  # np.clip, less overhead
        mujoco.mj_step(self.model, self.data)
        self._cache.clear()
        self.steps += 1

    # -- senses -----------------------------------------------------------------------------
    def _need(self, sense: str) -> None:
        if sense not in self.senses:
            raise SenseNotEnabledError(
                f"sense '{sense}' is not enabled for this infant (senses: "
                f"{', '.join(self.senses) or 'none'}); pass senses=(..., '{sense}') to build_infant"
            )

    def _cached(self, key: str, compute: Callable[[], Any]) -> Any:
        value = self._cache.get(key)
        if value is None:
            value = compute()
            for array in value if isinstance(value, tuple) else (value,):
                if isinstance(array, np.ndarray):
                    array.flags.writeable = False
            self._cache[key] = value
        return value

    def touch(self) -> np.ndarray:
        """Returns (num_sensors, 3) float32: force on each sensor in its body's frame (N)."""
        sensors, values = self.touch_sparse()
        return self._cached("touch", lambda: self.skin.dense(sensors, values))

    def touch_sparse(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`touch` as (sensors (M,) int64 sorted, forces (M, 3) float32): only the few
        sensors that feel a force (the others read zero). Cheaper than the dense vector."""
        self._need("touch")
        sensors, values, _ = self._touch_and_hands()
        return sensors, values

    def _touch_and_hands(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Sparse touch and hand contacts, computed together once per step (compiled)."""
        return self._cached(
            "touch_and_hands",
            lambda: self._contacts.touch_and_hands(self.data, self.hand_of_body),
        )

    def proprioception(self) -> np.ndarray:
        """Returns (6 * action_dim,) float32; layout in :class:`~.senses.Proprioception`."""
        self._need("proprioception")
        return self._cached("proprioception", lambda: self._proprio(self.data))

    def vestibular(self) -> np.ndarray:
        """Returns (6,) float32: head accelerometer (m/s^2) then gyro (rad/s), head frame."""
        self._need("vestibular")
        return self._cached("vestibular", lambda: vestibular(self.data))

    def _eye_renderer(self) -> vision.Eyes:
        self._need("eyes")
        if self._gl["eyes"] is None:
            labels = vision.geom_labels(self.model, self.hand_of_body)
            self._gl["eyes"] = vision.Eyes(self.model, self.eye_size, labels)
        return self._gl["eyes"]

    def eyes(self) -> np.ndarray:
        """Returns (2, H, W, 3) uint8 camera images, [left eye, right eye]."""
        return self._cached("eyes", lambda: self._eye_renderer().rgb(self.data))

    def eyes_segmentation(self) -> np.ndarray:
        """Returns (2, H, W) int32 labels: 0 background, ``hand_labels`` (left 1, right 2),
        3 other body parts, 4 scene (mattress, floor, toys)."""
        return self._cached("segmentation", lambda: self._eye_renderer().segmentation(self.data))

    def hand_visibility(self) -> np.ndarray:
        """Returns (2 eyes, 2 hands) bool: some pixel of the hand is in that eye's image; rows
        [left eye, right eye], columns [left hand, right hand]."""
        seg = self.eyes_segmentation()
        return self._cached(
            "visibility",
            lambda: np.array(
                [
                    [np.any(seg[e] == self.hand_labels[h]) for h in ("left", "right")]
                    for e in range(2)
                ]
            ),
        )

    def hand_contacts(self) -> np.ndarray:
        """Returns (2 hands, 68) bool: regions each hand (palm or fingers) touches this step;
        row 0 is the left hand, row 1 the right."""
        return self._touch_and_hands()[2]

    def render_view(self, width: int = 320, height: int = 240) -> np.ndarray:
        """Returns (height, width, 3) uint8 from the scene's third-person camera."""
        key = (int(width), int(height))
        views = self._gl["views"]
        if key not in views:
            views[key] = vision.fast_renderer(self.model, key[1], key[0])
        renderer = views[key]
        renderer.update_scene(self.data, camera="overview")
        return renderer.render()

    def describe(self) -> dict[str, Any]:
        """Cheap summary for ``devlearn info``: sizes, timing, actuators."""
        return {
            "scene": self.scene,
            "start": self.start,
            "appearance": self.appearance,
            "age_months": self.age_months,
            "senses": list(self.senses),
            "action_dim": self.action_dim,
            "touch_sensors": self.skin.num_sensors,
            "skin_regions": NUM_REGIONS,
            "regions_per_side": NUM_PARTS,
            "proprioception_size": self._proprio.size,
            "eye_size": self.eye_size,
            "physics_timestep": self.physics_timestep,
            "control_timestep": self.control_timestep,
            "episode_steps": self.episode_steps,
            "actuator_groups": {k: len(v) for k, v in self.actuator_groups.items()},
        }

    def close(self) -> None:
        """Free renderers (GL contexts); rendering again opens new ones."""
        _free_gl(self._gl)

    def __enter__(self) -> Infant:
        return self

    def __exit__(self, *exc_info: object) -> None:
        """Leaving a ``with build_infant(...) as infant:`` block closes the infant."""
        self.close()


_SKINS: dict[tuple[str, float | None], Skin] = {}


def _shared_skin(model: mujoco.MjModel, scene: str, age_months: float | None) -> Skin:
    """The skin of this scene's infant at this age, built once per process: a Skin is
    read-only, so the envs of a worker share one, and an age change builds one per worker."""
    key = (scene, age_months)
    if key not in _SKINS:
        if len(_SKINS) >= 8:  # a growing run passes through many ages: keep the latest few
            _SKINS.pop(next(iter(_SKINS)))
        layout = None if age_months is None else grown_layout(grown_body(age_months).table)
        _SKINS[key] = Skin(model, layout)
    return _SKINS[key]


def _free_gl(gl: dict[str, Any]) -> None:
    if gl["eyes"] is not None:
        gl["eyes"].close()
        gl["eyes"] = None
    for renderer in gl["views"].values():
        renderer.close()
    gl["views"].clear()


build_infant = Infant
"""Build the infant in a scene: the public name of :class:`Infant` (its arguments), as plugins,
environments and tests call it."""
