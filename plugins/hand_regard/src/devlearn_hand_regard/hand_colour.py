"""Hand colour boxes in HSV: percentiles of the hand tracks' pixels, minus background colours."""

from __future__ import annotations

import cv2
import numpy as np


def hsv_boxes(hsv: np.ndarray, low: float = 1.0, high: float = 99.0,
              margin: tuple[int, int, int] = (2, 8, 8)) -> list[list[int]]:
    """Percentile box of (N, 3) OpenCV HSV pixels, widened by ``margin``.

    Hue is circular (0..179): when the colours sit around red's wrap, the box is computed on
    shifted hues and returned as two boxes.
    """
    h = hsv[:, 0].astype(float)
    spans = []
    for shift in (0, 90):
        hs = (h + shift) % 180
        lo, hi = np.percentile(hs, [low, high])
        spans.append((hi - lo, shift, lo, hi))
    _, shift, h_lo, h_hi = min(spans)
    s_lo, v_lo = np.percentile(hsv[:, 1:], low, axis=0)
    s_hi, v_hi = np.percentile(hsv[:, 1:], high, axis=0)
    s_lo, v_lo = max(0, s_lo - margin[1]), max(0, v_lo - margin[2])
    s_hi, v_hi = min(255, s_hi + margin[1]), min(255, v_hi + margin[2])
    h_lo, h_hi = h_lo - margin[0] - shift, h_hi + margin[0] - shift
    boxes = []
    for lo, hi in ((h_lo, h_hi), (h_lo + 180, h_hi + 180), (h_lo - 180, h_hi - 180)):
        lo, hi = max(lo, 0), min(hi, 179)
        if lo <= hi:
            boxes.append([int(np.floor(lo)), int(np.floor(s_lo)), int(np.floor(v_lo)),
                          int(np.ceil(hi)), int(np.ceil(s_hi)), int(np.ceil(v_hi))])
    return boxes


def drop_background_boxes(boxes: list[list[int]], eyes: np.ndarray, max_coverage: float,
                          frames: int = 200) -> tuple[list[list[int]], list[list[int]]]:
    """Split boxes into kept and dropped by their mean pixel coverage over sample frames.

    Args:
        boxes: HSV boxes (see :func:`hsv_boxes`).
        eyes: (T, 2, H, W, 3) uint8 RGB babbling frames.
        max_coverage: Largest mean share of pixels a kept box may select.
        frames: Frames sampled.

    A hand never fills most of the view, so a colour box covering more than ``max_coverage``
    of the image on average must be catching background colours too.
    """
    index = np.linspace(0, len(eyes) - 1, min(frames, len(eyes))).astype(int)
    images = eyes[index].reshape(-1, *eyes.shape[2:])
    hsv = np.stack([cv2.cvtColor(np.ascontiguousarray(im), cv2.COLOR_RGB2HSV) for im in images])
    kept, dropped = [], []
    for box in boxes:
        inside = np.all((hsv >= box[:3]) & (hsv <= box[3:]), axis=-1)
        (kept if inside.mean() <= max_coverage else dropped).append(box)
    return kept, dropped
