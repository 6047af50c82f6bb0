"""Which hand is it: each hand's visibility predicted from its own arm's posture (issue #39).

Both mittens have one colour, so a blob's colour says "a hand", not which one, and in
BabyBench's scene both hands rise into view from below at the same places: attributing blobs
by image position was right about half the time with both arms moving (pair precision 0.55).
What does tell the hands apart is the body's own posture: a hand can be in view only when its
arm holds it up before the eyes, and the two arms are seldom both there.

The infant learns this while babbling one arm at a time (``babble(arms="alternate")``): on
every frame it knows which arm moved (the other hangs still, out of view) and whether the
calibrated colour detector sees a hand in each eye. Per hand and eye, a logistic regression
on the quadratic features of the angles that place that hand (its arm's shoulder and elbow,
and the head's moving joints) learns P(this eye sees this hand | posture), from the frames
where that arm babbled (seen or not) and those where it hung still (not seen). At run time a
blob goes to the hand whose posture makes it likelier to be in view (:func:`assign`). No
segmentation and no image position is used; the same model serves every policy, since it
reads only proprioception and the detector's blobs.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from devlearn_hand_regard.babbling import BabblingData

MIN_JOINT_SPREAD = 0.01
"""Joints whose angle spread over babbling (standard deviation, rad) is below this are left out
of the model: the head's held pitch and side tilt in BabyBench's scene say nothing, and
standardised they would blow up any tiny deviation."""
RIDGE = 1.0
"""Penalty on every weight but the intercept (standardised, quadratic features); the side
attribution was the same at 1 and 10 on held-out both-arm babbling (issue #39)."""
NEWTON_STEPS = 25
"""Newton (IRLS) iterations of the logistic fit; it converges in about ten."""
MIN_SEEN_FRAMES = 20
"""A hand seen in fewer babbling frames than this gets no model (nothing to learn from)."""


def quadratic_features(x: np.ndarray) -> np.ndarray:
    """[1, x, every product x_i x_j (i <= j)] of (N, k) inputs; returns (N, 1 + k + k(k+1)/2)."""
    i, j = np.triu_indices(x.shape[1])
    return np.concatenate([np.ones((len(x), 1)), x, x[:, i] * x[:, j]], axis=1)


def fit_logistic(features: np.ndarray, labels: np.ndarray, ridge: float = RIDGE) -> np.ndarray:
    """Ridge-penalised logistic regression by Newton's method (deterministic).

    Args:
        features: (N, F) inputs, first column the constant 1 (not penalised).
        labels: (N,) 0 or 1.
        ridge: Penalty on the other weights.
    Returns:
        (F,) weights.
    """
    penalty = np.full(features.shape[1], float(ridge))
    penalty[0] = 0.0
    weights = np.zeros(features.shape[1])
    for _ in range(NEWTON_STEPS):
        p = 1.0 / (1.0 + np.exp(-(features @ weights)))
        gradient = features.T @ (p - labels) + penalty * weights
        hessian = (features * (p * (1 - p))[:, None]).T @ features + np.diag(penalty + 1e-9)
        step = np.linalg.solve(hessian, gradient)
        weights -= step
        if np.abs(step).max() < 1e-8:
            break
    return weights


def visibility_labels(data: BabblingData, seen: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """What a one-arm-at-a-time babbling recording says about each hand's visibility.

    Args:
        data: The recording (``moving_arm`` set).
        seen: (T, 2 eyes) bool, the colour detector found a hand blob in that eye.
    Returns:
        labels: (T, 2 eyes, 2 hands) bool: hand h is in view of eye e (a blob was seen while
            arm h babbled alone; the still arm's hand hangs out of view).
        usable: (T,) bool, frames where one arm babbled alone (both-arm babbling tells nothing
            about which hand a blob is).
    """
    moving = data.moving_arm if data.moving_arm is not None else np.full(len(data), -1)
    usable = moving >= 0
    labels = np.zeros((len(data), 2, 2), dtype=bool)
    for hand in range(2):
        labels[:, :, hand] = seen & (moving == hand)[:, None]
    return labels, usable


def fit_visibility_model(
    recordings: list[tuple[BabblingData, np.ndarray]], ridge: float = RIDGE
) -> dict[str, Any]:
    """Learn P(eye e sees hand h | posture) from one-arm babbling recordings.

    Args:
        recordings: (recording, seen) pairs; ``seen`` (T, 2 eyes) bool as in
            :func:`visibility_labels`. Recordings without ``posture_joints`` or
            ``moving_arm`` are skipped.
        ridge: Penalty of :func:`fit_logistic`.
    Returns:
        ``joints`` (2 hands, k_h) proprioception indices, ``low``/``high`` (the babbling range,
        inputs are clipped to it), ``mean``/``scale`` (standardisation), ``weights`` (2 hands,
        F_h, 2 eyes) of :func:`quadratic_features`, ``frames`` and ``seen_frames`` per hand;
        empty when no recording babbled one arm at a time or a hand was seen in fewer than
        :data:`MIN_SEEN_FRAMES` frames.
    """
    postures, labels = [], []
    joints: list[list[int]] = []
    for data, seen in recordings:
        if not data.posture_joints or data.moving_arm is None:
            continue
        joints = data.posture_joints
        label, usable = visibility_labels(data, np.asarray(seen, dtype=bool))
        postures.append(np.asarray(data.proprioception, dtype=float)[usable])
        labels.append(label[usable])
    if not postures:
        return {}
    proprioception, label = np.concatenate(postures), np.concatenate(labels)
    model: dict[str, Any] = {key: [] for key in ("joints", "low", "high", "mean", "scale")}
    model.update(weights=[], frames=[], seen_frames=[])
    for hand in range(2):
        seen_frames = int(label[:, :, hand].any(axis=1).sum())
        if seen_frames < MIN_SEEN_FRAMES:
            return {}
        angles = proprioception[:, joints[hand]]
        kept = [
            j for j, spread in zip(joints[hand], angles.std(axis=0)) if spread >= MIN_JOINT_SPREAD
        ]
        x = proprioception[:, kept]
        mean, scale = x.mean(axis=0), x.std(axis=0)
        features = quadratic_features((x - mean) / scale)
        weights = [fit_logistic(features, label[:, eye, hand], ridge) for eye in range(2)]
        model["joints"].append(kept)
        model["low"].append(np.round(x.min(axis=0), 5).tolist())
        model["high"].append(np.round(x.max(axis=0), 5).tolist())
        model["mean"].append(np.round(mean, 5).tolist())
        model["scale"].append(np.round(scale, 5).tolist())
        model["weights"].append(np.round(np.stack(weights, axis=1), 5).tolist())
        model["frames"].append(len(x))
        model["seen_frames"].append(seen_frames)
    return model


def predict_visibility(model: dict[str, Any], proprioception: np.ndarray) -> np.ndarray:
    """P(eye e sees hand h) from the posture; returns (2 eyes, 2 hands) in [0, 1].

    Args:
        model: :func:`fit_visibility_model`'s result (non-empty).
        proprioception: (P,) one step's proprioception.
    """
    p = np.asarray(proprioception, dtype=float)
    out = np.zeros((2, 2))
    for hand in range(2):
        x = np.clip(p[model["joints"][hand]], model["low"][hand], model["high"][hand])
        z = (x - np.asarray(model["mean"][hand])) / np.asarray(model["scale"][hand])
        logits = quadratic_features(z[None])[0] @ np.asarray(model["weights"][hand])
        out[:, hand] = 1.0 / (1.0 + np.exp(-logits))
    return out


def assign(likelihood: np.ndarray, blobs: int) -> list[int]:
    """The hands one eye's blobs belong to, the likeliest explanation under the posture.

    Args:
        likelihood: (2 hands,) P(this eye sees hand h) from :func:`predict_visibility`.
        blobs: Hand blobs found in the eye (the colour says each is a hand).
    Returns:
        The hands in view: none without a blob; with one blob the likelier hand; with two,
        both hands when each is likelier in view than not (p > 0.5 each: then p_l p_r beats
        p_l (1 - p_r) and p_r (1 - p_l)), else the likelier hand alone (a hand split in two
        blobs, e.g. by the other arm's sleeve).
    """
    if blobs == 0:
        return []
    likely = int(np.argmax(likelihood))
    if blobs >= 2 and bool(np.all(likelihood > 0.5)):
        return [0, 1]
    return [likely]
