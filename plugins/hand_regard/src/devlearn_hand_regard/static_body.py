"""What of the body is always in view for a given head pose (legs, trunk), learned by babbling.

The whole infant is one skin colour, so a colour detector also fires on the legs, which the
sitting scene holds still. The trunk and legs never move, so whether a pixel shows them depends
only on where the head points: during babbling we keep, for sampled frames, the head pose and
the hand-colour mask. At run time the ``neighbours`` babbling frames with the nearest head
poses vote per pixel; pixels hand-coloured in at least ``fraction`` of them are the static body
(the babbling arms move, so they rarely reach that share) and are removed before blob search.
"""

from __future__ import annotations

import base64
from dataclasses import dataclass

import cv2
import numpy as np


@dataclass
class StaticBody:
    """Head poses and hand-colour masks of sampled babbling frames.

    Attributes:
        poses: (N, D) head joint angles (rad).
        masks: (N, 2, H, W) bool hand-colour masks of both eyes.
        neighbours: Frames voting per query.
        fraction: Share of votes making a pixel static body.
        max_distance: Head-pose distance (rad) beyond which no frame votes (unknown pose:
            nothing is removed).
    """

    poses: np.ndarray
    masks: np.ndarray
    neighbours: int = 20
    fraction: float = 0.4
    max_distance: float = 0.3

    def to_json(self) -> dict:
        """JSON-ready dict; masks as base64 of ``np.packbits``."""
        packed = np.packbits(self.masks.astype(bool), axis=None)
        return {
            "poses": np.round(self.poses, 4).tolist(),
            "mask_shape": list(self.masks.shape),
            "masks_packbits_base64": base64.b64encode(packed.tobytes()).decode("ascii"),
            "neighbours": self.neighbours,
            "fraction": self.fraction,
            "max_distance": self.max_distance,
        }

    @classmethod
    def from_json(cls, data: dict) -> StaticBody:
        """Inverse of :meth:`to_json`."""
        shape = tuple(data["mask_shape"])
        bits = np.frombuffer(base64.b64decode(data["masks_packbits_base64"]), np.uint8)
        masks = np.unpackbits(bits, count=int(np.prod(shape))).reshape(shape).astype(bool)
        return cls(np.asarray(data["poses"], float), masks, int(data["neighbours"]),
                   float(data["fraction"]), float(data["max_distance"]))

    def mask(self, head_pose: np.ndarray) -> np.ndarray:
        """Return (2, H, W) bool: the static body expected in view at ``head_pose`` (D,)."""
        distance = np.linalg.norm(self.poses - np.asarray(head_pose, float), axis=1)
        nearest = np.argsort(distance)[: self.neighbours]
        nearest = nearest[distance[nearest] <= self.max_distance]
        if len(nearest) == 0:
            return np.zeros(self.masks.shape[1:], bool)
        static = self.masks[nearest].mean(axis=0) >= self.fraction
        element = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))  # cover pose mismatch
        return np.stack([cv2.dilate(s.astype(np.uint8), element) > 0 for s in static])


def fit_static_body(head_pose: np.ndarray, eyes: np.ndarray, colour_mask, frames: int = 2000,
                    **options) -> StaticBody:
    """Sample babbling frames and keep their head poses and hand-colour masks.

    Args:
        head_pose: (T, D) head joint angles.
        eyes: (T, 2, H, W, 3) uint8 RGB.
        colour_mask: Function (H, W, 3) image -> (H, W) bool (the calibrated colour test).
        frames: Frames kept (evenly spaced).
        options: :class:`StaticBody` settings.
    """
    index = np.linspace(0, len(eyes) - 1, min(frames, len(eyes))).astype(int)
    masks = np.array([[colour_mask(image) for image in eyes[t]] for t in index])
    return StaticBody(np.asarray(head_pose[index], float), masks, **options)
