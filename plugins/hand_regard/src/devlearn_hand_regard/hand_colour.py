"""Colours: the babbling palette (k-means in Lab) and the hand colour boxes in HSV."""

from __future__ import annotations

import cv2
import numpy as np

from devlearn_hand_regard.babbling import BabblingData


def hsv_boxes(
    hsv: np.ndarray, low: float = 2.0, high: float = 98.0, margin: tuple[int, int, int] = (2, 8, 8)
) -> list[list[int]]:
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
            boxes.append(
                [
                    int(np.floor(lo)),
                    int(np.floor(s_lo)),
                    int(np.floor(v_lo)),
                    int(np.ceil(hi)),
                    int(np.ceil(s_hi)),
                    int(np.ceil(v_hi)),
                ]
            )
    return boxes


def drop_background_boxes(
    boxes: list[list[int]],
    eyes: np.ndarray,
    hand_pixels: np.ndarray,
    max_coverage: float = 0.25,
    min_purity: float = 0.6,
) -> tuple[list[list[int]], list[list[int]]]:
    """Split boxes into kept and dropped by what they select in sample frames.

    A hand never fills most of the view, so a box covering more than ``max_coverage`` of the
    image on average catches background colours. A box whose selected pixels are mostly *not*
    of the hand colour clusters (``purity`` below ``min_purity``; e.g. the shaded faces of toy
    blocks, as dark as shaded skin) catches other objects.

    Args:
        boxes: HSV boxes (see :func:`hsv_boxes`).
        eyes: (N, H, W, 3) uint8 RGB sample images.
        hand_pixels: (N, H, W) bool, pixels whose palette colour is a hand colour.
        max_coverage: Largest mean share of pixels a kept box may select.
        min_purity: Smallest share of a kept box's pixels that are hand-coloured clusters.
    Returns:
        (kept, dropped) boxes.
    """
    hsv = np.stack([cv2.cvtColor(np.ascontiguousarray(im), cv2.COLOR_RGB2HSV) for im in eyes])
    kept: list[list[int]] = []
    dropped: list[list[int]] = []
    for box in boxes:
        inside = np.all((hsv >= box[:3]) & (hsv <= box[3:]), axis=-1)
        purity = hand_pixels[inside].mean() if inside.any() else 0.0
        ok = inside.mean() <= max_coverage and purity >= min_purity
        (kept if ok else dropped).append(box)
    return kept, dropped


def lab_features(images: np.ndarray, lightness_weight: float = 0.5) -> np.ndarray:
    """Return (..., 3) float32 Lab colours of RGB uint8 images, lightness scaled down."""
    flat = np.ascontiguousarray(images.reshape(-1, 1, 3))
    lab = cv2.cvtColor(flat, cv2.COLOR_RGB2Lab).reshape(*images.shape[:-1], 3).astype(np.float32)
    lab[..., 0] *= lightness_weight
    return lab


def colour_palette(data: BabblingData, clusters: int, seed: int, frames: int = 200) -> np.ndarray:
    """Cluster the colours of ``frames`` evenly spaced frames; return (clusters, 3) Lab centres."""
    index = np.linspace(0, len(data) - 1, min(frames, len(data))).astype(int)
    pixels = lab_features(data.eyes[index]).reshape(-1, 3)
    pixels = np.random.default_rng(seed).permutation(pixels)[:200_000]
    cv2.setRNGSeed(seed)
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 0.5)
    # bestLabels=None (OpenCV allocates them); the stubs ask for an array
    _, _, centres = cv2.kmeans(pixels, clusters, None, criteria, 3, cv2.KMEANS_PP_CENTERS)  # type: ignore[call-overload]
    return centres


def label_image(image: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """Return (H, W) int: the nearest palette colour of every pixel of an RGB image."""
    features = lab_features(image)
    distance = ((features[..., None, :] - centres) ** 2).sum(-1)
    return distance.argmin(-1)
