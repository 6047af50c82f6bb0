"""Score a hand detector against the renderer's segmentation: record fresh babbling with the
segmentation of every frame (:func:`held_out`) and compare the detections with it frame by
frame (:func:`score`). The segmentation is used here only, never by the detector; a run's
calibration (``detector_store``) and the ``measure`` command both score with it."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, cast

import numpy as np

from devlearn_hand_regard.babbling import BabblingData, babble
from devlearn_hand_regard.evaluation import PAIRS, pair_name

if TYPE_CHECKING:
    from devlearn import Infant
    from devlearn_hand_regard.detector import HandDetector

LABELS = ("background", "left_hand", "right_hand", "body", "scene")
"""Segmentation labels (``devlearn.infant.vision``): 0..4."""


class SegmentationRecorder:
    """Wraps an infant; records the segmentation render whenever the eyes are read."""

    def __init__(self, infant: Infant) -> None:
        self.infant = infant
        self.segmentation: list[np.ndarray] = []

    def __getattr__(self, name: str) -> Any:
        return getattr(self.infant, name)

    def eyes(self) -> np.ndarray:
        """The eye images; their segmentation is kept in ``self.segmentation``."""
        self.segmentation.append(self.infant.eyes_segmentation().copy())
        return self.infant.eyes()


def held_out(
    infant: Infant,
    steps: int,
    seed: int,
    episode_steps: int | None = None,
    random_pose: bool = False,
    start: str = "babybench",
    hold_steps: int = 25,
) -> tuple[BabblingData, np.ndarray]:
    """Fresh babbling with the segmentation of every frame ((T, 2, H, W) int).

    Args:
        infant: The sitting infant.
        steps: Frames to record.
        seed: Seed of the actions and starts.
        episode_steps: Steps between resets (default: the infant's episode length).
        random_pose: Every episode from a random start (evaluation frames).
        start: Otherwise every episode from this start (``devlearn.infant.starts.STARTS``).
        hold_steps: Mean steps an arm's babbling action is held.
    """
    recorder = SegmentationRecorder(infant)
    data = babble(
        steps,
        seed=seed,
        infant=cast("Infant", recorder),  # a proxy: the infant, recording segmentations
        episode_steps=episode_steps,
        random_pose=random_pose,
        start=start,
        hold_steps=hold_steps,
    )
    return data, np.stack(recorder.segmentation)


def score(
    detector: HandDetector,
    data: BabblingData,
    segmentation: np.ndarray,
    clear_pixels: int = 20,
    posture: bool = True,
) -> dict:
    """Compare the detector's output with the segmentation, frame by frame.

    Args:
        detector: The detector.
        data: Frames to detect in.
        segmentation: (T, 2, H, W) labels of the same frames.
        clear_pixels: A hand showing at least this many pixels is "clearly visible".
        posture: Give the detector the proprioception (left/right from the predicted hand
            positions); False: from the hands' mean positions only.
    Returns:
        ``pairs``: per (eye, hand) name precision, recall, accuracy, recall on clearly visible
        hands and the share of steps the hand is in view; ``any_hand``: the same with the
        hands' identity ignored (is any hand in this eye?); ``pixels``: share of detected
        pixels per segmentation label; ``hand_pixel_recall``: share of hand pixels detected.
        Per pair, ``precision_pixels`` and ``recall_pixels`` take as truth at least
        ``clear_pixels`` of the hand's pixels (``devlearn eval``'s ``pixels`` criterion), and
        ``credited_absent`` is the share of steps the detector credits that pair while the
        hand shows no pixel in that eye (``credited_absent_max``: the largest over pairs).
    """
    conf = np.zeros((4, 2, 2))  # tp, fp, fn, tn per (eye, hand)
    absent = np.zeros((2, 2))  # steps a pair is detected while that hand shows no pixel
    conf_clear = np.zeros((4, 2, 2))  # the same against "clearly visible" (eval's ``pixels``)
    clear = np.zeros((2, 2, 2))  # clearly visible: (found, visible) per (eye, hand)
    anyh = np.zeros(4)
    labels = np.zeros(len(LABELS))
    hand_px = np.zeros(2)  # hand pixels detected, hand pixels in view
    own_px = np.zeros((3, 2))  # per hand: mask pixels on that hand, mask pixels, hand pixels
    for t in range(len(data)):
        proprioception = data.proprioception[t] if posture else None
        detections, masks = detector.detect(data.eyes[t], proprioception)
        for eye in range(2):
            seg = segmentation[t, eye]
            detected = masks[eye].any(0)
            labels += np.bincount(seg[detected], minlength=len(LABELS))[: len(LABELS)]
            is_hand = (seg == 1) | (seg == 2)
            hand_px += [(detected & is_hand).sum(), is_hand.sum()]
            for hand in range(2):
                n = int((seg == hand + 1).sum())
                own_px[:, hand] += [
                    (masks[eye, hand] & (seg == hand + 1)).sum(),
                    masks[eye, hand].sum(),
                    n,
                ]
                truth, found = n > 0, bool(detections[eye, hand])
                conf[_cell(truth, found), eye, hand] += 1
                absent[eye, hand] += found and n == 0
                conf_clear[_cell(n >= clear_pixels, found), eye, hand] += 1
                if n >= clear_pixels:
                    clear[:, eye, hand] += [found, 1]
            truth, found = bool(is_hand.any()), bool(detections[eye].any())
            anyh[_cell(truth, found)] += 1
    pairs = {}
    for eye, hand in PAIRS:
        tp, fp, fn, tn = conf[:, eye, hand]
        against_pixels = _stats(*conf_clear[:, eye, hand])
        pairs[pair_name(eye, hand)] = _stats(tp, fp, fn, tn) | {
            "clear_recall": (
                round(clear[0, eye, hand] / clear[1, eye, hand], 3) if clear[1, eye, hand] else None
            ),
            "clear_steps": int(clear[1, eye, hand]),
            "precision_pixels": against_pixels["precision"],
            "recall_pixels": against_pixels["recall"],
            "credited_absent": round(absent[eye, hand] / max(len(data), 1), 4),
        }
    tp, fp, fn, tn = conf.sum(axis=(1, 2))
    return {
        "steps": len(data),
        "pairs": pairs,
        "pairs_pooled": _stats(tp, fp, fn, tn)
        | {"clear_recall": round(clear[0].sum() / max(clear[1].sum(), 1), 3)},
        "any_hand": _stats(*anyh),
        "pixels": {k: round(v / max(labels.sum(), 1), 3) for k, v in zip(LABELS, labels)},
        "hand_pixel_recall": round(hand_px[0] / max(hand_px[1], 1), 3),
        "hand_pixels": {
            f"{side}_hand": {
                "precision": round(own_px[0, h] / max(own_px[1, h], 1), 3),
                "recall": round(own_px[0, h] / max(own_px[2, h], 1), 3),
            }
            for h, side in enumerate(("left", "right"))
        },
        "pair_mean": {
            k: _mean([p[k] for p in pairs.values()])
            for k in ("precision", "recall", "clear_recall", "precision_pixels", "recall_pixels")
        },
        "credited_absent_max": max(p["credited_absent"] for p in pairs.values()),
    }


def _cell(truth: bool, found: bool) -> int:
    """Confusion index: 0 true positive, 1 false positive, 2 false negative, 3 true negative."""
    return (0 if truth else 1) if found else (2 if truth else 3)


def _stats(tp: float, fp: float, fn: float, tn: float) -> dict:
    """Precision (None when nothing was detected), recall (None when nothing was in view),
    accuracy and the share of steps in view."""
    return {
        "precision": round(tp / (tp + fp), 3) if tp + fp else None,
        "recall": round(tp / (tp + fn), 3) if tp + fn else None,
        "accuracy": round((tp + tn) / max(tp + fp + fn + tn, 1), 3),
        "in_view": round((tp + fn) / max(tp + fp + fn + tn, 1), 3),
    }


def _mean(values: list) -> float | None:
    """Mean of the values that are not None (None if none is)."""
    values = [v for v in values if v is not None]
    return round(float(np.mean(values)), 3) if values else None
