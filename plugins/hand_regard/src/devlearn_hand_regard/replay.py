"""Replay a published policy's frames: record what it saw under ``devlearn eval``'s protocol
(images, proprioception, the segmentation as ground truth), once, then score any hand
attribution on them offline (issue #58 item 2, the adversarial check).

A recording is one ``.npz`` (:func:`save_frames` / :func:`load_frames`): ``eyes`` (T, 2, H, W,
3) uint8, ``proprioception`` (T, P) float32, ``segmentation`` (T, 2, H, W) uint8 (labels of
:data:`segmentation_score.LABELS`), ``episode`` (T,) int; one frame per decision, as the
behaviour's detector sees them. The segmentation is read by the scoring only, never by a
detector.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from devlearn_hand_regard.babbling import BabblingData


class FrameRecorder:
    """Wraps an infant: every time the eyes are read (once per decision, by the behaviour's
    facts), keeps the images, the proprioception and the segmentation; every reset starts a
    new episode."""

    def __init__(self, infant: Any) -> None:
        self.infant = infant
        self.eyes_seen: list[np.ndarray] = []
        self.proprioception_seen: list[np.ndarray] = []
        self.segmentation: list[np.ndarray] = []
        self.episode_seen: list[int] = []
        self.episodes = -1

    def __getattr__(self, name: str) -> Any:
        return getattr(self.infant, name)

    def reset(self, *args: Any, **kwargs: Any) -> Any:
        """The infant's reset; the frames after it belong to a new episode."""
        self.episodes += 1
        return self.infant.reset(*args, **kwargs)

    def eyes(self) -> np.ndarray:
        """The eye images; a copy of them, the proprioception and the segmentation are kept."""
        eyes = self.infant.eyes()
        self.eyes_seen.append(eyes.copy())
        self.proprioception_seen.append(np.asarray(self.infant.proprioception(), np.float32))
        self.segmentation.append(self.infant.eyes_segmentation().astype(np.uint8))
        self.episode_seen.append(max(self.episodes, 0))
        return eyes

    def frames(self) -> dict[str, np.ndarray]:
        """The recorded frames as :func:`save_frames` writes them."""
        return {
            "eyes": np.stack(self.eyes_seen),
            "proprioception": np.stack(self.proprioception_seen),
            "segmentation": np.stack(self.segmentation),
            "episode": np.asarray(self.episode_seen, dtype=np.int32),
        }


def record_policy(path: Path, episodes: int, seed: int = 0) -> dict[str, np.ndarray]:
    """Run a policy file under ``devlearn eval``'s protocol (its mean action, from its
    evaluation start, ``episodes`` x 1,000 steps, eval seed ``seed``), recording its frames.

    Returns:
        :meth:`FrameRecorder.frames` of the infant that played the episodes.
    """
    # devlearn eval's own loop, through the plugin kit's entry to it (plugins import only
    # devlearn, devlearn.api and devlearn.testing); one env in this process, so the factory's
    # infant is the one that plays
    from devlearn import build_infant
    from devlearn.testing import PluginRegistry, evaluate_policy

    recorders: list[FrameRecorder] = []

    def factory(scene: str, *args: Any, **options: Any) -> FrameRecorder:
        recorders.append(FrameRecorder(build_infant(scene, *args, **options)))
        return recorders[-1]

    evaluate_policy(
        "hand_regard", path, episodes, PluginRegistry(), infant_factory=factory, seed=seed
    )
    played = max(recorders, key=lambda r: len(r.eyes_seen))
    return played.frames()


def save_frames(path: str | Path, frames: dict[str, np.ndarray], **meta: Any) -> Path:
    """Write a recording (compressed) with ``meta`` as 0-d string arrays; return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    arrays: dict[str, Any] = {
        **frames,
        **{f"meta_{k}": np.asarray(str(v)) for k, v in meta.items()},
    }
    np.savez_compressed(path, **arrays)
    return path


def load_frames(path: str | Path) -> dict[str, np.ndarray]:
    """Read :func:`save_frames`'s recording (every array, ``meta_*`` included)."""
    with np.load(path) as data:
        return {k: data[k] for k in data.files}


def as_babbling(frames: dict[str, np.ndarray]) -> BabblingData:
    """The frames as a recording that :func:`segmentation_score.score` reads (no actions)."""
    steps = len(frames["eyes"])
    return BabblingData(
        eyes=frames["eyes"],
        proprioception=frames["proprioception"],
        actions=np.zeros((steps, 0), np.float32),
        arm_speed=np.zeros((steps, 2), np.float32),
        episode=np.asarray(frames["episode"]),
    )
