"""Which hand is it: each hand's visibility predicted from its own arm's posture (issue #39).

Both mittens have one colour, so a blob's colour says "a hand", not which one, and in
BabyBench's scene both hands rise into view from below at the same places: attributing blobs
by image position was right about half the time with both arms moving (pair precision 0.55).
What does tell the hands apart is the body's own posture: a hand can be in view only when its
arm holds it up before the eyes, and the two arms are seldom both there.

The infant learns this while babbling one arm at a time (``babble(arms="alternate")``): on
every frame it knows which arm moved (the other hangs still, out of view) and whether the
calibrated colour detector sees a hand in each eye. Per hand and eye, a logistic regression
on the cubic features of the angles that place that hand (its arm's shoulder and elbow, and
the head's moving joints) learns P(this eye sees this hand | posture), from the frames where
that arm babbled (seen or not) and those where it hung still (not seen), and from the other
arm's frames seen in a mirror (the arms are built as mirror images: the other hand at the
same angles, in the other eye, with the head turned the other way), which doubles what each
hand learns from. At run time a blob goes to the hand whose posture makes it likelier to be
in view (:func:`assign`). No segmentation and no image position is used; the same model
serves every policy, since it reads only proprioception and the detector's blobs.

Chosen by measurement (issue #39; per-pair precision / recall against ``pixels`` averaged
over five held-out seeds of both-arm babbling from BabyBench's start, 42,000 frames, learned
from 60,000 one-arm babbling steps): quadratic features 0.93 / 0.85, cubic 0.93 / 0.85,
quadratic with the mirror 0.93 / 0.84, cubic with the mirror 0.95 / 0.86; the oracle (each
blob given its true hand) 0.96 / 0.88. From the calibration's 10,000 steps alone cubic with
the mirror reached 0.83 / 0.76, with 10,000 more 0.94 / 0.85. Tried on one or two of those
seeds with the 10,000 steps and dropped: a small MLP (0.62 to 0.89 precision on one seed
depending on its initial weights), k nearest neighbours (at most 0.78 / 0.69), and
correlating a blob's motion with each arm's speed, the efference copy (0.42 to 0.53: near
chance; with both arms moving their speeds rise and fall alike, and a hand held still says
nothing).
"""

from __future__ import annotations

import itertools
from functools import lru_cache
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from devlearn_hand_regard.babbling import BabblingData

MIN_JOINT_SPREAD = 0.01
"""Joints whose angle spread over babbling (standard deviation, rad) is below this are left out
of the model: the head's held pitch and side tilt in BabyBench's scene say nothing, and
standardised they would blow up any tiny deviation."""
RIDGE = 1.0
"""Penalty on every weight but the intercept (standardised features); the side attribution
was the same at 0.1, 1 and 10 on held-out both-arm babbling (issue #39)."""
DEGREE = 3
"""Degree of the polynomial features of the posture."""
NEWTON_STEPS = 25
"""Newton (IRLS) iterations of the logistic fit; it converges in about ten."""
MIN_SEEN_FRAMES = 20
"""A hand seen in fewer babbling frames than this gets no model (nothing to learn from)."""


@lru_cache
def _monomials(inputs: int, degree: int) -> tuple[tuple[int, ...], ...]:
    """Index tuples of every monomial of ``inputs`` variables up to ``degree`` (1 first)."""
    return tuple(
        combination
        for d in range(degree + 1)
        for combination in itertools.combinations_with_replacement(range(inputs), d)
    )


@lru_cache
def _monomial_index(inputs: int, degree: int) -> np.ndarray:
    """(C, degree) columns of ``[1, x_0, ..., x_{k-1}]`` whose products are the monomials of
    :func:`_monomials`, each padded with the constant column 0 at its end."""
    rows = [[i + 1 for i in m] + [0] * (degree - len(m)) for m in _monomials(inputs, degree)]
    index = np.array(rows, dtype=np.intp).reshape(len(rows), degree)
    index.flags.writeable = False
    return index


def polynomial_features(x: np.ndarray, degree: int = DEGREE) -> np.ndarray:
    """Every monomial of (N, k) inputs up to ``degree``: [1, x_i, x_i x_j, ...] (i <= j <= ...);
    returns (N, C(k + degree, degree)), e.g. (N, 56) for k = 5 and degree 3.

    One gather and one product over ``[1, x]`` (the monomial's factors in order, then ones):
    the same numbers as multiplying each monomial's factors, in a few microseconds a row where
    a product per monomial took about a millisecond (this runs every step of a hand-regard run).
    """
    x = np.asarray(x, dtype=float)
    padded = np.concatenate([np.ones((len(x), 1)), x], axis=1)
    return np.prod(padded[:, _monomial_index(x.shape[1], degree)], axis=2)


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
    recordings: list[tuple[BabblingData, np.ndarray]],
    ridge: float = RIDGE,
    degree: int = DEGREE,
    mirror: bool = True,
) -> dict[str, Any]:
    """Learn P(eye e sees hand h | posture) from one-arm babbling recordings.

    Args:
        recordings: (recording, seen) pairs; ``seen`` (T, 2 eyes) bool as in
            :func:`visibility_labels`. Recordings without ``posture_joints`` or
            ``moving_arm`` are skipped.
        ridge: Penalty of :func:`fit_logistic`.
        degree: Of :func:`polynomial_features`.
        mirror: Each hand also learns from the other arm's frames seen in a mirror: that arm's
            angles (head turns with ``posture_mirror``'s signs), the eyes swapped.
    Returns:
        ``joints`` (2 hands, k_h) proprioception indices, ``low``/``high`` (the babbling range,
        inputs are clipped to it), ``mean``/``scale`` (standardisation), ``degree``,
        ``weights`` (2 hands, F, 2 eyes) of :func:`polynomial_features`, ``frames`` and
        ``seen_frames`` per hand (its own); empty when no recording babbled one arm at a time
        or a hand was seen in fewer than :data:`MIN_SEEN_FRAMES` frames.
    """
    postures, labels = [], []
    joints: list[list[int]] = []
    signs = np.zeros(0)
    for data, seen in recordings:
        if not data.posture_joints or data.moving_arm is None:
            continue
        joints = data.posture_joints
        signs = np.asarray(data.posture_mirror or np.ones(len(joints[0])), dtype=float)
        label, usable = visibility_labels(data, np.asarray(seen, dtype=bool))
        postures.append(np.asarray(data.proprioception, dtype=float)[usable])
        labels.append(label[usable])
    if not postures:
        return {}
    proprioception, label = np.concatenate(postures), np.concatenate(labels)
    seen_frames = [int(label[:, :, hand].any(axis=1).sum()) for hand in range(2)]
    if min(seen_frames) < MIN_SEEN_FRAMES:
        return {}
    model: dict[str, Any] = {key: [] for key in ("joints", "low", "high", "mean", "scale")}
    model.update(degree=degree, weights=[], frames=[], seen_frames=seen_frames)
    for hand in range(2):
        x = proprioception[:, joints[hand]]
        y = label[:, :, hand]
        if mirror:  # the other hand's frames, mirrored: same angles, other eye
            x = np.concatenate([x, proprioception[:, joints[1 - hand]] * signs])
            y = np.concatenate([y, label[:, ::-1, 1 - hand]])
        kept = x.std(axis=0) >= MIN_JOINT_SPREAD
        x = x[:, kept]
        mean, scale = x.mean(axis=0), x.std(axis=0)
        features = polynomial_features((x - mean) / scale, degree)
        weights = [fit_logistic(features, y[:, eye], ridge) for eye in range(2)]
        model["joints"].append([j for j, keep in zip(joints[hand], kept) if keep])
        model["low"].append(np.round(x.min(axis=0), 5).tolist())
        model["high"].append(np.round(x.max(axis=0), 5).tolist())
        model["mean"].append(np.round(mean, 5).tolist())
        model["scale"].append(np.round(scale, 5).tolist())
        model["weights"].append(np.round(np.stack(weights, axis=1), 5).tolist())
        model["frames"].append(len(proprioception))
    return model


_ARRAY_KEYS = ("low", "high", "mean", "scale", "weights")
"""The model's per-hand lists that :class:`VisibilityPredictor` turns into arrays."""


class VisibilityPredictor:
    """:func:`fit_visibility_model`'s model with its lists turned into arrays once, for the
    per-step prediction (:meth:`__call__`, the same numbers as :func:`predict_visibility`)."""

    def __init__(self, model: dict[str, Any]) -> None:
        self.degree = int(model["degree"])
        self.joints = [np.asarray(j, dtype=np.intp) for j in model["joints"]]
        arrays = {k: [np.asarray(v, dtype=float) for v in model[k]] for k in _ARRAY_KEYS}
        self.low, self.high = arrays["low"], arrays["high"]
        self.mean, self.scale, self.weights = arrays["mean"], arrays["scale"], arrays["weights"]

    def __call__(self, proprioception: np.ndarray) -> np.ndarray:
        """P(eye e sees hand h) from one step's (P,) proprioception: (2 eyes, 2 hands)."""
        p = np.asarray(proprioception, dtype=float)
        out = np.zeros((2, 2))
        for hand in range(2):
            x = np.clip(p[self.joints[hand]], self.low[hand], self.high[hand])
            z = (x - self.mean[hand]) / self.scale[hand]
            logits = polynomial_features(z[None], self.degree)[0] @ self.weights[hand]
            out[:, hand] = 1.0 / (1.0 + np.exp(-logits))
        return out


def predict_visibility(model: dict[str, Any], proprioception: np.ndarray) -> np.ndarray:
    """P(eye e sees hand h) from the posture; returns (2 eyes, 2 hands) in [0, 1]. (Per step,
    build a :class:`VisibilityPredictor` once and call it.)

    Args:
        model: :func:`fit_visibility_model`'s result (non-empty).
        proprioception: (P,) one step's proprioception.
    """
    return VisibilityPredictor(model)(proprioception)


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
