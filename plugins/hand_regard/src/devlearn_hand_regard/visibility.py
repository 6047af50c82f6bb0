"""When a hand counts as seen: the cone, pixels and any_pixel criteria of ``devlearn eval``."""

from __future__ import annotations

from typing import Any

import numpy as np

CONE_DEGREES = 15.0
"""``cone``: the hand body's centre lies within this angle of the eye camera's optical axis
(BabyBench's hand-regard rule; there the axis is taken from the wrong camera frame column,
here it is the camera's viewing direction, its frame's -z)."""
MIN_PIXELS = 20
"""``pixels``: at least this many pixels of the hand in the eye's segmentation render (64x64
eyes: 20 pixels is about a quarter of a fully visible mitten at arm's length)."""
CRITERIA = ("cone", "pixels", "any_pixel")
"""Visibility criteria, side by side in every hand-regard evaluation; ``cone`` is the headline."""
HEADLINE = "cone"
"""The criterion behind ``visibility`` and ``average`` in a hand-regard eval JSON."""


def axis_angles(data: Any, cameras: np.ndarray, bodies: np.ndarray) -> np.ndarray:
    """Angle between each camera's optical axis and the direction to each body's centre.

    A MuJoCo camera looks along the negative z axis of its frame (``cam_xmat``'s third
    column, negated). A body's centre is its centre of mass (``xipos``).

    Args:
        data: ``mujoco.MjData`` after ``mj_forward`` / ``mj_step``.
        cameras: (E,) camera ids (eyes).
        bodies: (H,) body ids (hands).
    Returns:
        (E, H) angles in degrees, in [0, 180].
    """
    out = np.empty((len(cameras), len(bodies)))
    for e, cam in enumerate(cameras):
        axis = -np.asarray(data.cam_xmat[cam]).reshape(3, 3)[:, 2]
        for h, body in enumerate(bodies):
            to_hand = np.asarray(data.xipos[body]) - np.asarray(data.cam_xpos[cam])
            norm = np.linalg.norm(to_hand)
            cos = float(axis @ to_hand / norm) if norm > 0 else 1.0
            out[e, h] = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    return out


def pixel_counts(segmentation: np.ndarray, labels: tuple[int, ...]) -> np.ndarray:
    """Pixels of each hand label in each eye's segmentation.

    Args:
        segmentation: (E, H, W) int labels.
        labels: (N,) label of each hand.
    Returns:
        (E, N) int64 counts.
    """
    seg = np.asarray(segmentation)
    return np.array([[int(np.count_nonzero(s == lab)) for lab in labels] for s in seg])


def visible(
    angles: np.ndarray,
    pixels: np.ndarray,
    cone_degrees: float = CONE_DEGREES,
    min_pixels: int = MIN_PIXELS,
) -> dict[str, np.ndarray]:
    """Each criterion's verdict per (eye, hand) pair.

    ``cone`` looks only at geometry (a hand behind a toy still counts, as in BabyBench);
    ``pixels`` and ``any_pixel`` only at the render (occlusion respected).

    Args:
        angles: (E, H) degrees from :func:`axis_angles`.
        pixels: (E, H) counts from :func:`pixel_counts`.
        cone_degrees: Half-angle of the cone.
        min_pixels: Pixels needed by ``pixels``.
    Returns:
        Criterion name -> (E, H) bool.
    """
    pixels = np.asarray(pixels)
    return {
        "cone": np.asarray(angles) <= cone_degrees,
        "pixels": pixels >= min_pixels,
        "any_pixel": pixels >= 1,
    }


def criteria_protocol(cone_degrees: float = CONE_DEGREES, min_pixels: int = MIN_PIXELS) -> dict:
    """The criteria's names and thresholds, as recorded in an eval JSON's protocol."""
    return {
        "cone": {
            "max_angle_deg": cone_degrees,
            "rule": "hand body centre within the angle of the eye camera's optical axis",
        },
        "pixels": {
            "min_pixels": min_pixels,
            "rule": "at least min_pixels of the hand in the eye's segmentation render",
        },
        "any_pixel": {"min_pixels": 1, "rule": "any pixel of the hand in the render"},
    }


def measure_visibility(infant) -> dict[str, np.ndarray]:
    """Every criterion's verdict for the real infant's current state.

    Args:
        infant: A :class:`devlearn.infant.Infant` with the ``eyes`` sense (cameras
            ``left_eye``/``right_eye``, bodies ``left_hand``/``right_hand``).
    Returns:
        Criterion name -> (2 eyes, 2 hands) bool.
    """
    import mujoco  # here, not at import: devlearn.infant sets MUJOCO_GL before mujoco loads

    model = infant.model
    cameras = np.array(
        [
            mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, f"{s}_eye")
            for s in ("left", "right")
        ]
    )
    bodies = np.array([model.body(f"{s}_hand").id for s in ("left", "right")])
    labels = (infant.hand_labels["left"], infant.hand_labels["right"])
    angles = axis_angles(infant.data, cameras, bodies)
    return visible(angles, pixel_counts(infant.eyes_segmentation(), labels))
