"""The eyes: two 64 x 64 cameras rendered headless (EGL), segmentation, and a third-person view."""

from __future__ import annotations

import mujoco
import numpy as np

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
    """A renderer with shadows, reflections, skybox, fog and haze off (cheap on Mesa)."""
    renderer = mujoco.Renderer(model, height=height, width=width)
    for flag in _OFF:
        renderer.scene.flags[flag] = False
    return renderer


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
        self.size = size

    def rgb(self, data: mujoco.MjData) -> np.ndarray:
        """Returns (2, H, W, 3) uint8, [left, right]."""
        out = np.empty((2, self.size, self.size, 3), dtype=np.uint8)
        for i, cam in enumerate(self.cameras):
            self.renderer.update_scene(data, camera=cam)
            self.renderer.render(out=out[i])
        return out

    def segmentation(self, data: mujoco.MjData) -> np.ndarray:
        """Returns (2, H, W) int32 labels (BACKGROUND, LEFT_HAND, RIGHT_HAND, BODY, SCENE)."""
        out = np.zeros((2, self.size, self.size), dtype=np.int32)
        self.renderer.enable_segmentation_rendering()
        try:
            for i, cam in enumerate(self.cameras):
                self.renderer.update_scene(data, camera=cam)
                ids = self.renderer.render()
                geom = (ids[..., 1] == mujoco.mjtObj.mjOBJ_GEOM) & (ids[..., 0] >= 0)
                out[i][geom] = self.labels[ids[..., 0][geom]]
        finally:
            self.renderer.disable_segmentation_rendering()
        return out

    def close(self) -> None:
        """Free the GL context."""
        self.renderer.close()
