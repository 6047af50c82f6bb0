"""Blob tracks for hand discovery (paper sec. II-B2, step 2 of :mod:`.calibration`).

Blob centroids of each colour cluster are linked frame to frame by nearest-neighbour matching
within each eye; a track ends when its blob is not found, and at resets.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from devlearn_hand_regard.babbling import BabblingData
from devlearn_hand_regard.detector import colour_blobs
from devlearn_hand_regard.hand_colour import label_image

if TYPE_CHECKING:
    from devlearn_hand_regard.detector import Blob


@dataclass
class Track:
    """A blob followed through consecutive frames of one eye and one colour cluster."""

    eye: int
    cluster: int
    steps: list[int] = field(default_factory=list)
    centroids: list[tuple[float, float]] = field(default_factory=list)
    areas: list[float] = field(default_factory=list)
    pixels: list[np.ndarray] = field(default_factory=list)  # flat pixel indices per frame
    rho: float = 0.0
    side: int = -1

    def motion(self, window: int) -> float:
        """Variance (pixels squared) of the centroid's displacement over ``window`` steps: how
        much the blob moves around, whatever its correlation."""
        c = np.asarray(self.centroids)
        if len(c) <= window:
            return 0.0
        return float(np.linalg.norm(c[window:] - c[:-window], axis=1).var())


def track_blobs(
    data: BabblingData,
    centres: np.ndarray,
    max_jump: float = 0.12,
    min_area: float = 0.002,
    max_area: float = 0.3,
) -> list[Track]:
    """Find colour blobs in every frame and link them into tracks.

    Args:
        data: The babbling recording.
        centres: (K, 3) palette from :func:`colour_palette`.
        max_jump: Largest centroid move between frames, as a fraction of the image width.
        min_area: Smallest blob, fraction of the image area.
        max_area: Largest blob, fraction of the image area.
    Returns:
        Every track (any length).
    """
    _, n_eyes, height, width, _ = data.eyes.shape
    area = height * width
    jump = max_jump * width
    active: dict[tuple[int, int], list[Track]] = {}
    done: list[Track] = []
    for t in range(len(data)):
        new_episode = t > 0 and data.episode[t] != data.episode[t - 1]
        for eye in range(n_eyes):
            labels = label_image(data.eyes[t, eye], centres)
            for k in range(len(centres)):
                blobs = colour_blobs(labels == k, min_area * area, max_area * area, kernel=3)
                previous = [] if new_episode else active.get((eye, k), [])
                if new_episode:
                    done += active.get((eye, k), [])
                # Greedy nearest-neighbour matching, closest pairs first.
                pairs = sorted(
                    (
                        np.hypot(
                            b.centroid[0] - tr.centroids[-1][0], b.centroid[1] - tr.centroids[-1][1]
                        ),
                        i,
                        j,
                    )
                    for i, b in enumerate(blobs)
                    for j, tr in enumerate(previous)
                )
                used_b, used_t, current = set(), set(), []
                for dist, i, j in pairs:
                    if dist > jump or i in used_b or j in used_t:
                        continue
                    used_b.add(i)
                    used_t.add(j)
                    current.append(previous[j])
                    _extend(previous[j], t, blobs[i])
                for i, b in enumerate(blobs):
                    if i not in used_b:
                        current.append(_extend(Track(eye, k), t, b))
                done += [tr for j, tr in enumerate(previous) if j not in used_t]
                active[(eye, k)] = current
    for tracks in active.values():
        done += tracks
    return done


def _extend(track: Track, step: int, blob: Blob) -> Track:
    track.steps.append(step)
    track.centroids.append(blob.centroid)
    track.areas.append(blob.area)
    track.pixels.append(np.flatnonzero(blob.mask).astype(np.int32))
    return track
