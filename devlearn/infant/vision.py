"""The eyes: two 64 x 64 cameras rendered headless (EGL), segmentation, and a third-person view."""

from __future__ import annotations

import atexit
import weakref
from collections.abc import Callable

import mujoco
import numpy as np

from devlearn.gl_backend import rendering_problem

# Segmentation labels of Infant.eyes_segmentation().
BACKGROUND, LEFT_HAND, RIGHT_HAND, BODY, SCENE = 0, 1, 2, 3, 4
HAND_LABELS = {"left": LEFT_HAND, "right": RIGHT_HAND}

_OFF = (
    mujoco.mjtRndFlag.mjRND_SHADOW,
    mujoco.mjtRndFlag.mjRND_REFLECTION,
    mujoco.mjtRndFlag.mjRND_SKYBOX,
    mujoco.mjtRndFlag.mjRND_FOG,
    mujoco.mjtRndFlag.mjRND_HAZE,
)


def fast_renderer(model: mujoco.MjModel, height: int, width: int) -> mujoco.Renderer:
    """A renderer with shadows, reflections, skybox, fog and haze off (cheap on Mesa).

    Raises:
        RuntimeError: ``MUJOCO_GL`` names no backend (one line saying so), or no OpenGL
            context opens.
    """
    if problem := rendering_problem():
        raise RuntimeError(problem)
    try:
        renderer = mujoco.Renderer(model, height=height, width=width)
    except mujoco.FatalError as exc:  # typically: mujoco imported before MUJOCO_GL was set
        raise RuntimeError(
            f"cannot open an OpenGL context ({exc}). mujoco picks its GL backend when it is first "
            "imported: import devlearn.infant before mujoco and dm_control, or set MUJOCO_GL=egl "
            "in the environment for headless rendering"
        ) from exc
    for flag in _OFF:
        renderer.scene.flags[flag] = False
    _track(renderer)
    return renderer


_LIVE: weakref.WeakSet = weakref.WeakSet()
_EXIT_HOOK: list[Callable[[], None]] = []


def _track(renderer: mujoco.Renderer) -> None:
    """Close live renderers at exit, before mujoco's own exit hook terminates the EGL display
    (hooks run last-registered first; mujoco registers its hook with the first context)."""
    _LIVE.add(renderer)
    if not _EXIT_HOOK:
        _EXIT_HOOK.append(atexit.register(_close_all))


def _close_all() -> None:
    for renderer in list(_LIVE):
        try:
            renderer.close()
        except Exception:  # noqa: BLE001 - best effort at interpreter exit
            pass


def geom_labels(model: mujoco.MjModel, hand_of_body: np.ndarray) -> np.ndarray:
    """Segmentation label of every geom, (ngeom,) int32: hands 1/2, other body 3, scene 4."""
    body = model.geom_bodyid
    labels = np.where(body == 0, SCENE, BODY).astype(np.int32)
    hand = hand_of_body[body]
    labels[hand == 0] = LEFT_HAND
    labels[hand == 1] = RIGHT_HAND
    return labels


class Eyes:
    """Renders both eye cameras with one reused renderer.

    Args:
        model: The compiled model (cameras "left_eye" and "right_eye").
        size: Image height and width in pixels.
        labels: (ngeom,) segmentation label per geom (see :func:`geom_labels`).
    """

    def __init__(self, model: mujoco.MjModel, size: int, labels: np.ndarray) -> None:
        self.renderer = fast_renderer(model, size, size)
        self.cameras = [
            mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, f"{s}_eye")
            for s in ("left", "right")
        ]
        self.labels = labels
        self._lut: np.ndarray | None = None
        self.size = size
        self.seg_renderer: mujoco.Renderer | None = None

    def rgb(self, data: mujoco.MjData) -> np.ndarray:
        """Returns (2, H, W, 3) uint8, [left, right]."""
        out = np.empty((2, self.size, self.size, 3), dtype=np.uint8)
        for i, cam in enumerate(self.cameras):
            self.renderer.update_scene(data, camera=cam)
            self.renderer.render(out=out[i])
        return out

    def segmentation(self, data: mujoco.MjData) -> np.ndarray:
        """Returns (2, H, W) int32 labels (BACKGROUND, LEFT_HAND, RIGHT_HAND, BODY, SCENE)."""
        renderer = self.seg_renderer
        if renderer is None:
            # A second renderer drawing every geom in its id colour (MuJoCo's segmentation
            # mode), decoded here: mujoco.Renderer's own decoding walks the scene's geoms in
            # Python each frame (~7 ms).
            renderer = self.seg_renderer = fast_renderer(self.renderer.model, self.size, self.size)
            renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SEGMENT] = True
            renderer.scene.flags[mujoco.mjtRndFlag.mjRND_IDCOLOR] = True
        out = np.empty((2, self.size, self.size), dtype=np.int32)
        pixels = np.empty((self.size, self.size, 3), dtype=np.uint8)
        for i, cam in enumerate(self.cameras):
            renderer.update_scene(data, camera=cam)
            lut = self._segment_labels(renderer.scene)
            renderer.render(out=pixels)
            segid = pixels.astype(np.int32)
            code = segid[..., 0] + (segid[..., 1] << 8) + (segid[..., 2] << 16)  # segid + 1
            out[i] = lut.take(np.minimum(code, len(lut) - 1))
        return out

    def _segment_labels(self, scene: mujoco.MjvScene) -> np.ndarray:
        """Label of each segmentation colour code (segid + 1; 0 = nothing drawn)."""
        if self._lut is None or len(self._lut) != scene.ngeom + 1:
            lut = np.full(scene.ngeom + 1, BACKGROUND, dtype=np.int32)
            for i in range(scene.ngeom):
                geom = scene.geoms[i]
                if geom.segid >= 0 and geom.objtype == mujoco.mjtObj.mjOBJ_GEOM:
                    lut[geom.segid + 1] = self.labels[geom.objid]
            self._lut = lut
        return self._lut

    def close(self) -> None:
        """Free the GL contexts."""
        self.renderer.close()
        if self.seg_renderer is not None:
            self.seg_renderer.close()
