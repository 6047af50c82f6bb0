"""Pictures of the infant: the 68-region body map (docs/images/body_map.png), the eyes' view and
the body from birth to 24 months (docs/images/growth.png), drawn as BGR arrays and encoded to an
image file's bytes here; ``devlearn picture`` writes them (through :mod:`devlearn.files`)."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import cv2
import mujoco
import numpy as np

from devlearn.infant.infant import build_infant
from devlearn.infant.regions import NUM_PARTS, PART_NAMES
from devlearn.infant.scenes import SCENE_GROUP

if TYPE_CHECKING:
    from devlearn.infant.infant import Infant

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp")
"""The picture files ``devlearn picture`` writes (OpenCV encodes each by its extension)."""
# Looking down at both hands held in front, toys on the floor beyond.
EYES_POSE = {"head_tilt": 0.95, "shoulder_flexion": 0.6, "elbow": 1.0, "shoulder_abduction": -0.3}


def part_colours() -> np.ndarray:
    """(34, 3) RGB in [0, 1]: 34 distinct colours (matplotlib's tab20, then tab20b)."""
    from matplotlib import colormaps

    # both are ListedColormaps (with .colors); the registry's stubs say Colormap
    palette = list(colormaps["tab20"].colors) + list(colormaps["tab20b"].colors)  # type: ignore[attr-defined]
    return np.array(palette[:NUM_PARTS])[:, :3]


def region_colours() -> np.ndarray:
    """(68, 3) RGB in [0, 1]: the part's colour, the right side a little darker."""
    part = part_colours()
    return np.concatenate([part, 0.75 * part])


def _alone(
    infant: Infant,
    camera: mujoco.MjvCamera,
    size: tuple[int, int],
    decorate: Callable[[mujoco.MjvScene], None] | None = None,
    extra_geoms: int = 0,
) -> np.ndarray:
    """Render the infant without its surroundings, on white; ``decorate(scene)`` may change
    the scene's geoms or add up to ``extra_geoms`` before the render. Returns (H, W, 3) RGB."""
    option = mujoco.MjvOption()
    option.geomgroup[SCENE_GROUP] = 0
    renderer = mujoco.Renderer(
        infant.model, height=size[1], width=size[0], max_geom=extra_geoms + 500
    )
    try:
        renderer.update_scene(infant.data, camera=camera, scene_option=option)
        if decorate is not None:
            decorate(renderer.scene)
        image = renderer.render()
        renderer.enable_depth_rendering()
        depth = renderer.render()
        image[depth >= depth.max() * 0.999] = 255  # white background
        return image
    finally:
        renderer.close()


def _sensor_view(infant: Infant, camera: mujoco.MjvCamera, size: tuple[int, int]) -> np.ndarray:
    """Render the infant without its surroundings, each sensor a dot in its region's colour."""
    data, skin = infant.data, infant.skin

    def dots(scene: mujoco.MjvScene) -> None:
        for i in range(scene.ngeom):  # the body itself pale grey under the dots
            scene.geoms[i].rgba[:] = (0.82, 0.82, 0.82, 1.0)
        rot = data.xmat[skin.sensor_body].reshape(-1, 3, 3)
        world = data.xpos[skin.sensor_body] + np.einsum("nij,nj->ni", rot, skin.sensor_pos)
        radius = 0.42 * skin.body_spacing[skin.sensor_body]
        rgba = np.concatenate([region_colours()[skin.sensor_region], np.ones((len(world), 1))], 1)
        eye = np.eye(3).ravel()
        for pos, r, colour in zip(world, radius, rgba):
            geom = scene.geoms[scene.ngeom]
            mujoco.mjv_initGeom(geom, mujoco.mjtGeom.mjGEOM_SPHERE, [r, r, r], pos, eye, colour)
            # mjv_initGeom leaves these as whatever the buffer held (a random ``transparent``
            # changed the picture from run to run): set them so the picture is deterministic.
            geom.category, geom.transparent = mujoco.mjtCatBit.mjCAT_DECOR, 0
            geom.objtype, geom.objid, geom.segid, geom.camdist = 0, -1, -1, 0.0
            scene.ngeom += 1

    return _alone(infant, camera, size, dots, extra_geoms=skin.num_sensors)


def _legend(height: int, width: int) -> np.ndarray:
    panel = np.full((height, width, 3), 255, dtype=np.uint8)
    colours = (part_colours() * 255).astype(int)
    step = min(26, (height - 40) // NUM_PARTS)
    cv2.putText(panel, "part (left | right)", (10, 22), cv2.FONT_HERSHEY_SIMPLEX, 0.55, (0,) * 3, 1)
    for i, name in enumerate(PART_NAMES):
        y = 40 + i * step
        for k, scale in enumerate((1.0, 0.75)):
            colour = tuple(int(c * scale) for c in colours[i][::-1])  # BGR for cv2
            cv2.rectangle(panel, (10 + 22 * k, y), (28 + 22 * k, y + step - 6), colour, -1)
        cv2.putText(panel, name, (60, y + step - 9), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0,) * 3, 1)
    return panel


def body_map_picture(width: int = 420, height: int = 900) -> np.ndarray:
    """Draw the body map: front and back views of the infant, sensors coloured by region.

    Args:
        width, height: Size of each view in pixels.

    Returns:
        (height, 2 * width + 260, 3) uint8 BGR.
    """
    infant = build_infant("crib", senses=("touch",))
    try:
        infant.reset(np.random.default_rng(0))
        centre = infant.data.xpos[infant.model.body("lower_body").id].copy()
        centre[0] += 0.034  # halfway between sole and crown (body table)
        views = []
        for azimuth, elevation, title in ((0.0, -89.9, "front"), (180.0, 89.9, "back")):
            camera = mujoco.MjvCamera()
            camera.lookat[:], camera.distance = centre, 1.12
            camera.azimuth, camera.elevation = azimuth, elevation
            image = np.ascontiguousarray(_sensor_view(infant, camera, (width, height))[..., ::-1])
            cv2.putText(image, title, (12, 30), cv2.FONT_HERSHEY_SIMPLEX, 0.9, (40,) * 3, 2)
            views.append(image)
        picture = np.concatenate(views + [_legend(height, 260)], axis=1)
    finally:
        infant.close()
    return picture


GROWTH_AGES = (0.0, 6.0, 12.0, 18.0, 24.0)
"""Ages (months) ``devlearn picture growth`` draws."""
GROWTH_POSE = {"left_shoulder_abduction": 0.25, "right_shoulder_abduction": 0.25}
"""Every other joint at 0 (legs straight, as length is measured), the arms a little away from
the trunk so that they show."""


def growth_picture(
    ages: tuple[float, ...] = GROWTH_AGES, width: int = 250, height: int = 520
) -> np.ndarray:
    """Draw the infant at each of ``ages`` side by side, from the front, at one scale: soles
    on one line, a grey line every 10 cm, each labelled with its age, crown-heel length and
    mass (:mod:`devlearn.infant.growth`; WHO's medians).

    Args:
        ages: Ages in months (0 to 24).
        width, height: Size of each infant's panel in pixels.

    Returns:
        (height, A * width + (A - 1) * 4, 3) uint8 BGR, for A ages.
    """
    from devlearn.infant.growth import grown_body, standing_extent

    distance, margin = 1.35, 0.04  # camera above the hip (m); space below the soles (m)
    panels = []
    for age in ages:
        infant = build_infant("crib", senses=(), age_months=age)
        try:
            model, data = infant.model, infant.data
            mujoco.mj_resetData(model, data)
            for joint, angle in GROWTH_POSE.items():
                data.qpos[model.joint(joint).qposadr[0]] = angle
            mujoco.mj_forward(model, data)
            # lying in the crib, the body's long axis is world x (head at +x): the soles at
            # the bottom of every panel, in the same place
            body = grown_body(age)
            hip = data.xpos[model.body("hip").id]
            sole = hip[0] + standing_extent(body.table)[0]
            span = 2 * distance * np.tan(np.radians(model.vis.global_.fovy) / 2)  # m per panel
            camera = mujoco.MjvCamera()
            camera.lookat[:] = (sole - margin + span / 2, 0.0, hip[2])
            camera.distance, camera.azimuth, camera.elevation = distance, 0.0, -89.9
            image = np.ascontiguousarray(_alone(infant, camera, (width, height))[..., ::-1])
        finally:
            infant.close()
        per_metre = height / span
        for cm in range(0, 101, 10):  # the scale: a line every 10 cm above the soles
            row = int(round(height - (margin + cm / 100) * per_metre))
            if 0 <= row < height:
                line = image[row]
                line[np.all(line == 255, axis=1)] = (215, 215, 215)
        for text, row, size in (
            (f"{age:g} months", 26, 0.7),
            (f"{100 * body.length:.1f} cm, {body.mass:.1f} kg", 50, 0.5),
        ):
            cv2.putText(image, text, (10, row), cv2.FONT_HERSHEY_SIMPLEX, size, (30,) * 3, 2)
        panels.append(image)
    note = "a line every 10 cm"
    cv2.putText(panels[0], note, (10, 74), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (90,) * 3, 1)
    gap = np.full((height, 4, 3), 255, dtype=np.uint8)
    parts = [panels[0]]
    for panel in panels[1:]:
        parts += [gap, panel]
    return np.concatenate(parts, axis=1)


def eyes_picture(
    scale: int = 4, scene: str = "sitting_babybench", overview: bool = True
) -> np.ndarray:
    """Draw what the two eyes see at the scene's rest (its initial state), left | right,
    64 x 64 each, and beside them the third-person view of the same moment.

    In ``sitting_babybench`` (hand regard's default, BabyBench's scene) the head is pitched
    0.4 rad down and the arms hang at the sides: the eyes see the floor, the toy blocks at the
    bottom edge and the far wall, and no hand. ``sitting`` shows that scene with the hands
    raised before the eyes (:data:`EYES_POSE`), the picture of runs before issue #29.

    Args:
        scale: Each eye pixel is drawn as scale x scale pixels.
        scene: ``sitting_babybench`` or ``sitting``.
        overview: Add the third-person view on the right.

    Returns:
        (64 * scale, W, 3) uint8 BGR: the eyes and, with ``overview``, the third-person view.
    """
    infant = build_infant(scene, senses=("eyes",))
    try:
        infant.reset(np.random.default_rng(0), start="rest")
        if scene == "sitting":
            for joint, angle in EYES_POSE.items():
                for name in (joint, f"left_{joint}", f"right_{joint}"):
                    if name in infant.actuator_names:
                        infant.data.qpos[infant.model.joint(name).qposadr[0]] = angle
            mujoco.mj_forward(infant.model, infant.data)
        frames = []
        for image, title in zip(infant.eyes(), ("left eye", "right eye")):
            big = cv2.resize(image, None, fx=scale, fy=scale, interpolation=cv2.INTER_NEAREST)
            big = np.ascontiguousarray(big[..., ::-1])
            cv2.putText(big, title, (8, 22), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (20,) * 3, 2)
            frames.append(big)
        height = frames[0].shape[0]
        if overview:
            view = np.ascontiguousarray(infant.render_view(height * 4 // 3, height)[..., ::-1])
            cv2.putText(view, "third person", (8, 22), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (20,) * 3, 2)
            frames.append(view)
        gap = np.full((height, 6, 3), 255, dtype=np.uint8)
        parts = [frames[0]]
        for frame in frames[1:]:
            parts += [gap, frame]
        picture = np.concatenate(parts, axis=1)
    finally:
        infant.close()
    return picture


def encode_picture(picture: np.ndarray, suffix: str = ".png") -> bytes:
    """A BGR uint8 picture as the bytes of an image file of type ``suffix``
    (:data:`IMAGE_SUFFIXES`; PNG at its highest compression).

    Raises:
        ValueError: OpenCV cannot encode that type.
    """
    try:
        ok, encoded = cv2.imencode(suffix, picture, [cv2.IMWRITE_PNG_COMPRESSION, 9])
    except cv2.error:
        ok = False
    if not ok:
        raise ValueError(f"OpenCV cannot write a '{suffix}' picture")
    return encoded.tobytes()
