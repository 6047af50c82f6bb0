"""A recording reduced to what a side attribution reads: per frame and eye, the colour
detector's hand blobs (centroid, area), the proprioception and the episode, plus, for scoring
only, the ground truth (each hand's pixels in each eye, each blob's majority hand label).

A few hundred bytes a frame where the images take 24 kB: the attribution rules of issue #58
(:mod:`~devlearn_hand_regard.contingency`) and the rules before it are scored on tables like
these offline, and a recorded fooling episode fits in a test's data file.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from devlearn_hand_regard.detector import Blob, HandDetector

MAX_BLOBS = 2
"""Blobs kept per eye (the detector reports at most two hands per eye, largest first)."""


@dataclass
class BlobTable:
    """T frames of blobs.

    Attributes:
        blobs: (T, 2 eyes, MAX_BLOBS, 3) float32 [x, y, area] in pixels, NaN where no blob
            (blobs largest first).
        proprioception: (T, P) float32.
        episode: (T,) int32.
        hand_pixels: (T, 2 eyes, 2 hands) int32, each hand's pixels in the segmentation
            (ground truth; -1 when unknown).
        blob_hand: (T, 2 eyes, MAX_BLOBS) int8, the hand whose pixels are most of the blob
            (0 left, 1 right; -1 neither or no blob): ground truth, for scoring only.
        moving_arm: (T,) int8, the babbling arm (-1: both or unknown).
        image_width: Pixels across an eye image.
        other_arm_hangs: The arm that did not babble hung limp (action 0, ``babble(arms=
            "alternate")``), rather than holding a posture (``"turns"``).
    """

    blobs: np.ndarray
    proprioception: np.ndarray
    episode: np.ndarray
    hand_pixels: np.ndarray
    blob_hand: np.ndarray
    moving_arm: np.ndarray
    image_width: int = 64
    other_arm_hangs: bool = False

    def __len__(self) -> int:
        return len(self.blobs)

    def count(self, t: int, eye: int) -> int:
        """Blobs in frame ``t``, eye ``eye``."""
        return int(np.isfinite(self.blobs[t, eye, :, 0]).sum())

    def save(self, path: str | Path) -> Path:
        """Write the table as a compressed ``.npz``; return the path."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(
            path,
            blobs=self.blobs.astype(np.float32),
            proprioception=self.proprioception.astype(np.float32),
            episode=self.episode.astype(np.int32),
            hand_pixels=self.hand_pixels.astype(np.int32),
            blob_hand=self.blob_hand.astype(np.int8),
            moving_arm=self.moving_arm.astype(np.int8),
            image_width=np.asarray(self.image_width),
            other_arm_hangs=np.asarray(self.other_arm_hangs),
        )
        return path

    @classmethod
    def load(cls, path: str | Path) -> BlobTable:
        """Read :meth:`save`'s file."""
        with np.load(path) as data:
            return cls(
                blobs=data["blobs"],
                proprioception=data["proprioception"],
                episode=data["episode"],
                hand_pixels=data["hand_pixels"],
                blob_hand=data["blob_hand"],
                moving_arm=data["moving_arm"],
                image_width=int(data["image_width"]),
                other_arm_hangs=bool(data["other_arm_hangs"])
                if "other_arm_hangs" in data
                else False,
            )

    def concatenate(self, other: BlobTable) -> BlobTable:
        """This table then ``other`` (its episodes renumbered after this table's)."""
        offset = int(self.episode.max()) + 1 if len(self) else 0
        return BlobTable(
            blobs=np.concatenate([self.blobs, other.blobs]),
            proprioception=np.concatenate([self.proprioception, other.proprioception]),
            episode=np.concatenate([self.episode, other.episode + offset]),
            hand_pixels=np.concatenate([self.hand_pixels, other.hand_pixels]),
            blob_hand=np.concatenate([self.blob_hand, other.blob_hand]),
            moving_arm=np.concatenate([self.moving_arm, other.moving_arm]),
            image_width=self.image_width,
            other_arm_hangs=self.other_arm_hangs and other.other_arm_hangs,
        )


def blob_row(found: list[Blob]) -> np.ndarray:
    """(MAX_BLOBS, 3) [x, y, area] of the first blobs, NaN-padded."""
    row = np.full((MAX_BLOBS, 3), np.nan, np.float32)
    for i, blob in enumerate(found[:MAX_BLOBS]):
        row[i] = (blob.centroid[0], blob.centroid[1], blob.area)
    return row


def tabulate(
    detector: HandDetector,
    eyes: np.ndarray,
    proprioception: np.ndarray,
    episode: np.ndarray,
    segmentation: np.ndarray | None = None,
    moving_arm: np.ndarray | None = None,
    hand_labels: tuple[int, int] = (1, 2),
    other_arm_hangs: bool = False,
) -> BlobTable:
    """Reduce recorded frames to a :class:`BlobTable` with ``detector``'s colour step.

    Args:
        detector: A calibrated detector (its colour boxes and blob sizes are used).
        eyes: (T, 2, H, W, 3) uint8.
        proprioception: (T, P).
        episode: (T,) episode index.
        segmentation: (T, 2, H, W) labels (ground truth) or None.
        moving_arm: (T,) the babbling arm, or None (-1).
        hand_labels: Segmentation labels of the left and right hand.
        other_arm_hangs: See :class:`BlobTable`.
    """
    steps = len(eyes)
    blobs = np.full((steps, 2, MAX_BLOBS, 3), np.nan, np.float32)
    pixels = np.full((steps, 2, 2), -1, np.int32)
    owner = np.full((steps, 2, MAX_BLOBS), -1, np.int8)
    for t in range(steps):
        for eye in range(2):
            found = detector.blobs(eyes[t, eye])
            blobs[t, eye] = blob_row(found)
            if segmentation is None:
                continue
            seg = segmentation[t, eye]
            for hand in range(2):
                pixels[t, eye, hand] = int(np.count_nonzero(seg == hand_labels[hand]))
            for i, blob in enumerate(found[:MAX_BLOBS]):
                inside = seg[blob.mask]
                counts = [int(np.count_nonzero(inside == lab)) for lab in hand_labels]
                if max(counts) * 2 > len(inside):
                    owner[t, eye, i] = int(np.argmax(counts))
    return BlobTable(
        blobs=blobs,
        proprioception=np.asarray(proprioception, np.float32),
        episode=np.asarray(episode, np.int32),
        hand_pixels=pixels,
        blob_hand=owner,
        moving_arm=(
            np.full(steps, -1, np.int8) if moving_arm is None else np.asarray(moving_arm, np.int8)
        ),
        image_width=int(eyes.shape[3]),
        other_arm_hangs=other_arm_hangs,
    )
