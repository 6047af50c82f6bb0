"""When a hand counts as seen: the criteria of ``devlearn eval`` other than the detector's own
(``pixels``, ``babybench``, ``cone``, ``any_pixel``), from the scene's geometry and renders."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from devlearn import Infant

CONE_DEGREES = 15.0
"""``cone``: the hand body's centre lies within this angle of the eye camera's true optical
axis (the camera's viewing direction, its frame's -z). Not BabyBench's rule: see
:data:`BABYBENCH_DEGREES`."""
BABYBENCH_DEGREES = 15.0
"""``babybench``: BabyBench's official counter (its ``fovy / 2`` with ``fovy = 30``): the angle
between the eye *body's* -z axis and the eye-to-hand vector (body origins) is under this. The
eye body's -z is not the camera's axis: it points 90 degrees below it, toward the lap (facts
sec. 3b), in BabyBench's MIMo as in our infant, whose eye cameras sit in their bodies the same
way."""
MIN_PIXELS = 20
"""``pixels``: at least this many pixels of the hand in the eye's segmentation render (64x64
eyes: 20 pixels is about a quarter of a fully visible mitten at arm's length)."""
CRITERIA = ("pixels", "babybench", "cone", "any_pixel")
"""Ground-truth criteria, side by side with the detector's own detections (``detector``,
the headline) in every hand-regard evaluation."""
HEADLINE = "detector"
"""The criterion behind ``visibility`` and ``average`` in a hand-regard eval JSON: the
calibrated detector's own detections, the paper's measure (Table III, "% of steps with valid
detection"). Evaluations before issue #29 had ``cone`` here."""
DETECTOR_TRUTH = "pixels"
"""The criterion the detector's precision and recall are measured against."""


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


def babybench_angles(data: Any, eye_bodies: np.ndarray, hand_bodies: np.ndarray) -> np.ndarray:
    """BabyBench's hand-regard angles, as its ``_info`` computes them: between each eye body's
    -z axis (``-xmat[:, 2]``) and the vector from the eye body's origin to the hand body's
    origin (``xpos``, not the centre of mass).

    Args:
        data: ``mujoco.MjData`` after ``mj_forward`` / ``mj_step``.
        eye_bodies: (E,) body ids (``left_eye``, ``right_eye``).
        hand_bodies: (H,) body ids (``left_hand``, ``right_hand``).
    Returns:
        (E, H) angles in degrees, in [0, 180].
    """
    out = np.empty((len(eye_bodies), len(hand_bodies)))
    for e, eye in enumerate(eye_bodies):
        axis = -np.asarray(data.xmat[eye]).reshape(3, 3)[:, 2]
        for h, hand in enumerate(hand_bodies):
            to_hand = np.asarray(data.xpos[hand]) - np.asarray(data.xpos[eye])
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
    babybench: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Each criterion's verdict per (eye, hand) pair.

    ``cone`` and ``babybench`` look only at geometry (a hand behind a toy still counts, as in
    BabyBench); ``pixels`` and ``any_pixel`` only at the render (occlusion respected).

    Args:
        angles: (E, H) degrees from :func:`axis_angles`.
        pixels: (E, H) counts from :func:`pixel_counts`.
        cone_degrees: Half-angle of the cone.
        min_pixels: Pixels needed by ``pixels``.
        babybench: (E, H) degrees from :func:`babybench_angles`; None leaves it out.
    Returns:
        Criterion name -> (E, H) bool, in :data:`CRITERIA` order.
    """
    pixels = np.asarray(pixels)
    out = {"pixels": pixels >= min_pixels}
    if babybench is not None:
        out["babybench"] = np.asarray(babybench) < BABYBENCH_DEGREES  # strict, as its code
    out["cone"] = np.asarray(angles) <= cone_degrees
    out["any_pixel"] = pixels >= 1
    return out


def criteria_protocol(cone_degrees: float = CONE_DEGREES, min_pixels: int = MIN_PIXELS) -> dict:
    """The criteria's names and thresholds, as recorded in an eval JSON's protocol."""
    return {
        "detector": {
            "rule": "the calibrated detector's own detection of that hand in that eye's image "
            "(the paper's measure, Table III)"
        },
        "pixels": {
            "min_pixels": min_pixels,
            "rule": "at least min_pixels of the hand in the eye's segmentation render",
        },
        "babybench": {
            "max_angle_deg": BABYBENCH_DEGREES,
            "rule": "BabyBench's official counter as its code computes it: eye body's -z axis "
            "(90 degrees below the camera's optical axis) within the angle of the eye-to-hand "
            "vector (body origins)",
        },
        "cone": {
            "max_angle_deg": cone_degrees,
            "rule": "hand body centre within the angle of the eye camera's true optical axis",
        },
        "any_pixel": {"min_pixels": 1, "rule": "any pixel of the hand in the render"},
    }


def measure_visibility(infant: Infant) -> dict[str, np.ndarray]:
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
    eyes = np.array([model.body(f"{s}_eye").id for s in ("left", "right")])
    labels = (infant.hand_labels["left"], infant.hand_labels["right"])
    angles = axis_angles(infant.data, cameras, bodies)
    return visible(
        angles,
        pixel_counts(infant.eyes_segmentation(), labels),
        babybench=babybench_angles(infant.data, eyes, bodies),
    )
