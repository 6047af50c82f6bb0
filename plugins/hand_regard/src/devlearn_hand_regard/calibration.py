"""Unsupervised hand discovery from a babbling recording (paper sec. II-B2).

1. **Candidate blobs.** Colours are clustered (k-means in CIE Lab, lightness down-weighted so
   one object's lit and shaded sides stay together); every colour cluster's mask in every
   frame is cleaned by morphological opening/closing and split into contours, keeping
   object-sized ones (a generic 0.2%..30% of the image, nothing hand-specific).
2. **Tracks.** Blob centroids are linked frame to frame by nearest-neighbour matching within
   each eye and colour cluster; a track ends when its blob is not found, and at resets.
3. **Correlation.** For every track, the centroid's displacement over a short window (minus
   the eye's median displacement over all tracks) is correlated in time with each arm's
   joint-speed magnitude, both first regressed on the head's speed (a partial correlation: the
   head's own motion moves everything in view). ``rho_k`` is the best over both arms and lags
   0..``max_lag``.
4. **Hands.** Tracks with ``rho_k > 0.6`` are hands, of the arm that correlates best. Short
   tracks of other things (a toy whose outline the passing arm occludes) also reach 0.6 by
   chance, but they barely move; the hand colour is the colour cluster whose correlated tracks
   carry the most motion (frames x variance of their displacement), along with any cluster
   carrying at least half as much, unless its purity (share of its tracked pixels that are in
   hand tracks) is under half the purest's: a colour the hand shares with the body is not
   the hand's. The HSV ranges (percentiles of those tracks' pixels,
   background-like boxes dropped), the expected size and each hand's image-position
   statistics come from their blobs.
"""

from __future__ import annotations

import cv2
import numpy as np

from devlearn_hand_regard.babbling import BabblingData
from devlearn_hand_regard.correlation import ego_motion, head_speeds, track_correlation
from devlearn_hand_regard.detector import DetectorParams
from devlearn_hand_regard.hand_colour import (
    colour_palette,
    drop_background_boxes,
    hsv_boxes,
    label_image,
)
from devlearn_hand_regard.tracks import Track, track_blobs

__all__ = ["CalibrationError", "Track", "calibrate", "position_model", "track_blobs"]


def position_model(
    hands: list[Track],
    proprioception: np.ndarray,
    ridge: float = 4.0,
    min_frames: int = 20,
    max_error: float | None = None,
    episode: np.ndarray | None = None,
) -> dict:
    """Learn where each hand appears in view from the body's posture (for left/right).

    For each arm, a ridge regression from [1, eye - 0.5, standardised joint angles] to the
    centroids of the hand tracks attributed to it (the arm they correlated with). Joint angles
    are the first J of the proprioception's 6 J values (its documented [qpos, qvel, ...]
    layout). Both eyes share the posture's weights; ``eye - 0.5`` gives their offset.

    Args:
        hands: Hand tracks (``side`` set).
        proprioception: (T, P) the recording's proprioception.
        ridge: Penalty on every weight but the intercept (standardised angles; in frames: it
            weighs like this many frames pulling the weights to 0, so short babbling, with
            few hand frames, relies more on the mean position).
        min_frames: Fewest frames of either hand for a model.
        max_error: When given, the model is validated first: fitted on the hand tracks of
            every other babbling episode (``episode``; without it, every other track of each
            arm) and tested on the rest (then the other way round), and kept only
            if its median error on unseen tracks is at most this many pixels. A posture model
            that predicts worse than this would send blobs to the wrong hand, or (predicting a
            hand outside the image) to none.
        episode: (T,) babbling episode of each step (``BabblingData.episode``): folds by
            episode, so that tracks of one episode's postures are not on both sides.
    Returns:
        ``joint_mean``, ``joint_scale`` and ``weights`` (2 hands, 2 + J, 2), see
        :class:`DetectorParams`, and ``validation_error_px`` when validated; empty when a hand
        has too few frames, P < 6, or the validation error exceeds ``max_error``.
    """
    if max_error is not None:
        error = _validation_error(hands, proprioception, ridge, min_frames, episode)
        if error is None or error > max_error:
            return {}
        model = position_model(hands, proprioception, ridge, min_frames)
        return {**model, "validation_error_px": round(error, 2)} if model else {}
    n_joints = proprioception.shape[1] // 6
    if n_joints == 0:
        return {}
    angles = np.asarray(proprioception[:, :n_joints], dtype=float)
    mean, scale = angles.mean(0), angles.std(0) + 1e-6
    weights = []
    for side in range(2):
        tracks = [t for t in hands if t.side == side]
        steps = np.concatenate([t.steps for t in tracks]) if tracks else np.zeros(0, int)
        if len(steps) < min_frames:
            return {}
        eye = np.concatenate([np.full(len(t.steps), t.eye - 0.5) for t in tracks])
        x = np.c_[np.ones(len(steps)), eye, (angles[steps] - mean) / scale]
        y = np.concatenate([t.centroids for t in tracks])
        penalty = np.full(x.shape[1], float(ridge))
        penalty[0] = 0.0
        w = np.linalg.solve(x.T @ x + np.diag(penalty), x.T @ y)
        weights.append(np.round(w, 4).tolist())
    return {
        "joint_mean": np.round(mean, 5).tolist(),
        "joint_scale": np.round(scale, 5).tolist(),
        "weights": weights,
    }


def _validation_error(
    hands: list[Track],
    proprioception: np.ndarray,
    ridge: float,
    min_frames: int,
    episode: np.ndarray | None = None,
) -> float | None:
    """Median pixel error of :func:`position_model` on hand tracks it was not fitted on
    (two folds: every other babbling episode, or every other track of each arm); None when a
    fold has too few frames."""
    errors = []
    for fold in range(2):
        train, test = [], []
        for side in range(2):
            tracks = [t for t in hands if t.side == side]
            keys = [
                int(episode[t.steps[0]]) if episode is not None else i for i, t in enumerate(tracks)
            ]
            train += [t for k, t in zip(keys, tracks) if k % 2 != fold]
            test += [t for k, t in zip(keys, tracks) if k % 2 == fold]
        model = position_model(train, proprioception, ridge, min_frames)
        if not model or not test:
            return None
        mean, scale = np.asarray(model["joint_mean"]), np.asarray(model["joint_scale"])
        for t in test:
            angles = np.asarray(proprioception[t.steps, : len(mean)], dtype=float)
            x = np.c_[np.ones(len(t.steps)), np.full(len(t.steps), t.eye - 0.5)]
            x = np.c_[x, (angles - mean) / scale]
            predicted = x @ np.asarray(model["weights"][t.side])
            errors.append(np.linalg.norm(predicted - np.asarray(t.centroids), axis=1))
    return float(np.median(np.concatenate(errors))) if errors else None


def _share_in_boxes(hsv: np.ndarray, boxes: list[list[int]]) -> float:
    """Share of (N, 3) HSV pixels inside any of ``boxes`` (1.0 when there are no pixels)."""
    if len(hsv) == 0:
        return 1.0
    inside = np.zeros(len(hsv), bool)
    for box in boxes:
        inside |= np.all((hsv >= box[:3]) & (hsv <= box[3:]), axis=1)
    return float(inside.mean())


class CalibrationError(RuntimeError):
    """Babbling found no hand (too short a recording, or hands never in view)."""


def calibrate(
    data: BabblingData,
    *,
    threshold: float = 0.6,
    clusters: int = 12,
    seed: int = 0,
    window: int = 4,
    max_lag: int = 2,
    min_track: int = 30,
    min_cluster_share: float = 0.5,
    min_purity_share: float = 0.5,
    max_coverage: float = 0.25,
    ridge: float = 4.0,
    max_position_error: float = 0.25,
    max_colour_confusion: float = 0.05,
    per_hand_colours: bool = False,
) -> DetectorParams:
    """Discover the hands in a babbling recording and calibrate the detector.

    Args:
        data: The babbling recording.
        threshold: Correlation above which a track is a hand (paper: 0.6).
        clusters: Colours in the palette (enough that a small distinct colour, the hands', is
            not merged with a similar toy colour).
        seed: Seed of k-means.
        window: Steps over which displacement and arm speed are compared (smooths pixel noise).
        max_lag: Largest lag (steps) of the arm speed tried.
        min_track: Shortest track (steps) whose correlation is trusted.
        min_cluster_share: A colour cluster joins the hand colours when its correlated tracks
            carry at least this share of the strongest cluster's motion (frames x
            :meth:`Track.motion`).
        min_purity_share: Of those clusters, keep the ones whose purity (the share of all
            their tracked blob pixels that lie in hand tracks) is at least this share of the
            purest one's: a hand colour moves with the arm wherever it appears, while a colour
            the hand shares with the rest of the body (a forearm's shaded skin, also on the
            legs and trunk) mostly does not.
        max_coverage: A colour box selecting more than this share of all pixels (mean over the
            recording) is background-like (the floor seen between the fingers) and dropped.
        ridge: Regularisation of the posture-to-position model (:func:`position_model`).
        max_position_error: The posture model is kept only if its median error on hand
            tracks it was not fitted on is at most this share of the image width; otherwise
            the hands' mean positions attribute the blobs.
        max_colour_confusion: Each hand's colour boxes are also learned from its own tracks;
            when at most this share of either hand's pixels falls in the other hand's boxes
            (two differently coloured mittens), the detector tells the hands apart by colour
            (``side_hsv_ranges``); otherwise by position.
        per_hand_colours: Choose each hand's colour clusters among its own tracks only
            (motion and purity per hand). Only when the tracks' sides are reliable, i.e. the
            recording babbled one arm at a time (``babble(arms="alternate")``): then a hand
            seen rarely still gets its own colour. Otherwise (both arms babbling, where a side
            with few tracks would pick the forearm's skin) the colours are chosen over all
            hand tracks and split by hand afterwards.
    Returns:
        The detector parameters, with a ``calibration`` report.
    Raises:
        CalibrationError: No track correlated above ``threshold``.
    """
    n_steps, n_eyes, height, width, _ = data.eyes.shape
    centres = colour_palette(data, clusters, seed)
    tracks = track_blobs(data, centres)
    head = head_speeds(data)
    ego = ego_motion([t for t in tracks if len(t.steps) > window], n_steps, n_eyes, window)
    candidates = [t for t in tracks if len(t.steps) >= min_track]
    for tr in candidates:
        tr.rho, tr.side = track_correlation(tr, data.arm_speed, head, ego, window, max_lag)
    hands = [t for t in candidates if t.rho > threshold]
    report = {
        "babbling_steps": int(n_steps),
        "tracks": len(tracks),
        "tracks_scored": len(candidates),
        "hand_tracks": len(hands),
        "threshold": threshold,
        "rho_hand_tracks": sorted((round(t.rho, 3) for t in hands), reverse=True)[:20],
        "rho_other_tracks_max": round(
            max((t.rho for t in candidates if t.rho <= threshold), default=0.0), 3
        ),
    }
    if not hands:
        raise CalibrationError(
            f"no blob track correlated with the arms above {threshold} ({len(candidates)} "
            f"tracks of >= {min_track} steps, best {report['rho_other_tracks_max']}); babble "
            "for more steps"
        )
    tracked = np.bincount([t.cluster for t in tracks], [sum(t.areas) for t in tracks], clusters)
    motion = np.zeros((2, clusters))
    keep_side: list[list[int]] = [[], []]
    if per_hand_colours:  # each hand's colours, chosen among its own tracks
        for side in range(2):
            own = [t for t in hands if t.side == side]
            if not own:
                continue
            motion[side] = np.bincount(
                [t.cluster for t in own], [len(t.steps) * t.motion(window) for t in own], clusters
            )
            in_own = np.bincount([t.cluster for t in own], [sum(t.areas) for t in own], clusters)
            purity = in_own / np.maximum(tracked, 1)
            keep = [
                k
                for k in range(clusters)
                if motion[side, k] >= min_cluster_share * motion[side].max()
            ]
            best = max(purity[k] for k in keep)
            keep_side[side] = [k for k in keep if purity[k] >= min_purity_share * best]
        keep = sorted(set(keep_side[0]) | set(keep_side[1]))
    else:  # the hand colours over all hand tracks; each hand's own colours among them
        total = np.bincount(
            [t.cluster for t in hands], [len(t.steps) * t.motion(window) for t in hands], clusters
        )
        in_hands = np.bincount([t.cluster for t in hands], [sum(t.areas) for t in hands], clusters)
        purity = in_hands / np.maximum(tracked, 1)
        keep = [k for k in range(clusters) if total[k] >= min_cluster_share * total.max()]
        best = max(purity[k] for k in keep)
        keep = [k for k in keep if purity[k] >= min_purity_share * best]
        for side in range(2):
            own = [t for t in hands if t.side == side and t.cluster in keep]
            motion[side] = np.bincount(
                [t.cluster for t in own], [len(t.steps) * t.motion(window) for t in own], clusters
            )
            keep_side[side] = [k for k in keep if motion[side, k] > 0]
    hands = [t for t in hands if t.cluster in keep_side[t.side]]
    index = np.linspace(0, n_steps - 1, min(200, n_steps)).astype(int)
    sample = data.eyes[index].reshape(-1, height, width, 3)
    labels = np.stack([label_image(im, centres) for im in sample])
    side_boxes: list[list[list[int]]] = [[], []]
    dropped: list[list[int]] = []
    side_pixels: list[np.ndarray] = []
    for side in range(2):
        pixels = [
            data.eyes[s, t.eye].reshape(-1, 3)[p]
            for t in hands
            if t.side == side
            for s, p in zip(t.steps, t.pixels)
        ]
        if not pixels:
            side_pixels.append(np.zeros((0, 3), np.uint8))
            continue
        hsv = cv2.cvtColor(np.concatenate(pixels)[:, None, :], cv2.COLOR_RGB2HSV)[:, 0, :]
        side_pixels.append(hsv)
        boxes = []
        for k in keep_side[side]:
            boxes += hsv_boxes(
                hsv[
                    np.concatenate(
                        [
                            np.full(len(p), t.cluster == k)
                            for t in hands
                            if t.side == side
                            for p in t.pixels
                        ]
                    )
                ]
            )
        side_boxes[side], gone = drop_background_boxes(
            boxes, sample, np.isin(labels, keep), max_coverage
        )
        dropped += gone
    boxes = side_boxes[0] + [b for b in side_boxes[1] if b not in side_boxes[0]]
    if not boxes:
        raise CalibrationError(
            f"every hand colour found also covers most of the view (background); dropped {dropped}"
        )
    confusion = [_share_in_boxes(side_pixels[side], side_boxes[1 - side]) for side in range(2)]
    distinct = all(side_boxes) and max(confusion) <= max_colour_confusion
    areas = np.concatenate([t.areas for t in hands])
    means = np.zeros((n_eyes, 2, 2))
    for eye in range(n_eyes):
        for side in range(2):
            points = [c for t in hands if t.eye == eye and t.side == side for c in t.centroids]
            if points:
                means[eye, side] = np.mean(points, axis=0)
            else:  # never seen: assume the mirror image of the other hand (or a default side)
                other = [c for t in hands if t.eye == eye and t.side != side for c in t.centroids]
                x, y = np.mean(other, axis=0) if other else (width * (0.25 + 0.5 * side), height)
                means[eye, side] = (width - 1 - x, y) if other else (x, y)
    report.update(
        hand_cluster_motion=[
            {str(k): round(float(m[k])) for k in np.argsort(-m) if m[k] > 0} for m in motion
        ],
        hand_clusters=[[int(k) for k in side] for side in keep_side],
        hand_colour_confusion=[round(c, 3) for c in confusion],
        hands_told_by_colour=bool(distinct),
        dropped_background_boxes=dropped,
        hand_frames={
            f"eye{e}_side{s}": int(sum(len(t.steps) for t in hands if t.eye == e and t.side == s))
            for e in range(n_eyes)
            for s in range(2)
        },
        palette_lab=np.round(centres, 1).tolist(),
    )
    return DetectorParams(
        hsv_ranges=boxes,
        side_hsv_ranges=side_boxes if distinct else [],
        min_area=float(max(0.5 * np.percentile(areas, 2), 0.002 * height * width)),
        max_area=float(2.0 * np.percentile(areas, 98)),
        expected_area=float(np.median(areas)),
        hand_means=means.tolist(),
        image_size=(height, width),
        calibration=report,
        position_model=position_model(
            hands,
            data.proprioception,
            ridge,
            max_error=max_position_error * width,
            episode=data.episode,
        ),
    )
