"""Step 3 of hand discovery (:mod:`devlearn_hand_regard.calibration`): how well a blob
track's own motion follows an arm's joint speed, with the head's motion removed."""

from __future__ import annotations

import numpy as np

from devlearn_hand_regard.babbling import BabblingData
from devlearn_hand_regard.tracks import Track


def ego_motion(tracks: list[Track], steps: int, n_eyes: int, window: int) -> np.ndarray:
    """Return (steps, n_eyes, 2): per step, the median windowed displacement of all tracks.

    Everything in view shifts when the head turns; the median over all blobs estimates that
    shift (NaN where fewer than three blobs were tracked over the window).
    """
    moves: list[list[list[np.ndarray]]] = [[[] for _ in range(n_eyes)] for _ in range(steps)]
    for tr in tracks:
        c = np.asarray(tr.centroids)
        for i in range(window, len(c)):
            moves[tr.steps[i]][tr.eye].append(c[i] - c[i - window])
    out = np.full((steps, n_eyes, 2), np.nan)
    for t in range(steps):
        for eye in range(n_eyes):
            if len(moves[t][eye]) >= 3:
                out[t, eye] = np.median(np.asarray(moves[t][eye]), axis=0)
    return out


def _residual(y: np.ndarray, covariate: np.ndarray) -> np.ndarray:
    """``y`` minus its least-squares fit on [1, covariate] (covariate (n, k), k may be 0)."""
    x = np.c_[np.ones(len(y)), covariate]
    return y - x @ np.linalg.lstsq(x, y, rcond=None)[0]


def track_correlation(
    track: Track,
    arm_speed: np.ndarray,
    head_speed: np.ndarray,
    ego: np.ndarray,
    window: int,
    max_lag: int,
    min_speed_share: float = 0.25,
) -> tuple[float, int]:
    """Best correlation of a track's own motion with either arm's speed, head motion removed.

    Only arms that moved during the track are candidates: an arm whose mean joint speed over
    the track is under ``min_speed_share`` of the fastest arm's cannot have carried a hand
    across the view. Correlation ignores scale, and a still arm jostled by the moving one
    (its speed ~1% of the other's) follows the same rhythm: without this rule, tracks of the
    babbling arm's hand went to the still arm's side (issue #29, one arm babbling at a time).

    The centroid's displacement over ``window`` steps (minus the eye's median displacement)
    is compared with each arm's mean joint speed over the same steps, ``lag`` steps earlier.
    Both are first regressed on the head's mean speed (a partial correlation): a toy block
    moves in view only when the head turns, and the head also sways when the arms swing.

    Args:
        track: The track.
        arm_speed: (T, 2) arm joint-speed magnitudes.
        head_speed: (T,) head joint-speed magnitude (zeros when unknown).
        ego: (T, n_eyes, 2) from :func:`ego_motion`.
        window: Steps per displacement.
        max_lag: Largest lag tried.
        min_speed_share: Arms slower than this share of the fastest are not candidates.
    Returns:
        (rho, side): the correlation and the arm (0 left, 1 right) achieving it.
    """
    c = np.asarray(track.centroids)
    steps = np.asarray(track.steps)
    move = c[window:] - c[:-window]
    shift = ego[steps[window:], track.eye]
    move = move - np.where(np.isnan(shift), 0.0, shift)
    displacement = np.linalg.norm(move, axis=1)
    moving = arm_speed[steps].mean(axis=0)
    moving = moving >= min_speed_share * moving.max()
    best, side = 0.0, -1
    for lag in range(max_lag + 1):
        idx = steps[window:, None] - lag - np.arange(window)[None, :]
        if idx.min() < 0:
            continue
        head = head_speed[idx].mean(axis=1)[:, None]
        d = _residual(displacement, head)
        for s in np.flatnonzero(moving):
            a = _residual(arm_speed[idx, s].mean(axis=1), head)
            if d.std() < 1e-9 or a.std() < 1e-9:
                continue
            rho = float(np.corrcoef(d, a)[0, 1])
            if rho > best:
                best, side = rho, int(s)
    return best, side


def head_speeds(data: BabblingData) -> np.ndarray:
    """Return (T,) head joint-speed magnitude from the recorded head pose (finite differences;
    zeros when the recording has no head pose)."""
    head_pose = data.head_pose
    assert head_pose is not None  # BabblingData.__post_init__ makes it (T, 0) at least
    if head_pose.shape[1] == 0:
        return np.zeros(len(data))
    speed = np.zeros(len(data))
    speed[1:] = np.linalg.norm(np.diff(head_pose, axis=0), axis=1)
    speed[1:][data.episode[1:] != data.episode[:-1]] = 0.0  # no motion across a reset
    return speed
