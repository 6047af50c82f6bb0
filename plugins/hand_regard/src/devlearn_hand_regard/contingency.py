"""Which hand is it, from where each arm puts its hand and which blob moves with which arm
(issue #58; ``hand_attribution=contingency``; measured, not a default).

Issue #39's rule gave a blob to the hand whose arm's posture made it likelier in view; its
policies learned postures one-arm babbling never showed (the left hand across the midline, in
the right eye), where both hands were rated near zero and the larger near-zero took the blob:
an absent right hand was credited on 8-95% of steps. Infants tell their hands apart by
contingency (Bahrick and Watson 1985; Rochat): the hand that moves in view when an arm moves
is that arm's hand. This module learns from babbling, per arm and eye (the arm's shoulder and
elbow angles and the head's swivel: the visibility model's joints, standardised):

1. **Where the arm puts its hand** (:func:`fit_contingency_model`): the image place (x, y,
   sqrt(area)) of the blobs seen at the :data:`NEIGHBOURS` nearest babbled postures within
   :data:`SUPPORT_RADIUS` (none: the posture is out of the babbling's range, the hand is not
   credited there whatever the image shows), with that guess's spread on other episodes
   (capped at :data:`MAX_SIGMA`); and a smooth quadratic regression of the same places, whose
   differences are the arm's predicted image motion (joint velocities mapped into the image,
   head turns included).
2. **Which blob moves with which arm**: over the last :data:`WINDOW` decisions, the cosine of
   the blob's image displacements with each arm's predicted ones; the blob follows the arm
   with the larger cosine (above :data:`MIN_COSINE`), or an arm when both are still.
3. **Where babbling saw the hand out of that eye** (:meth:`ContingencyModel.out_of_view`).

A blob is credited to a side only when the evidence agrees (:meth:`ContingencyAttribution.
step`): in place and moving with that arm, the same side in every largest consistent pairing
of blobs and hands, the other hand accounted for (seen out of that eye at its posture, or
placed by its own model), and issue #39's visibility model assigning it that side too;
otherwise no side.

The labels come from babbling without the segmentation (:func:`contingency_labels`): one arm
at a time with the other hanging limp (every blob is the babbling arm's), and
``babble(arms="turns", random_pose=True)``: both arms anywhere (crossings included) taking
turns, a blob that moves while one arm moves being that arm's hand, a still blob while it
moves fast the other's. Validation and the adversarial replay of every published policy:
``python -m devlearn_hand_regard.contingency_check`` (``results/hand_regard/i58_attribution``:
no absent hand credited on 10 of 11 published policies, 5% on one; recall far below issue
#39's rule, babbling shows hands too seldom for a place model this local).

Per decision: about 0.9 ms (k-d tree queries, two polynomial feature rows per hand, the
visibility model; measured on a loaded core), beside a render of both eyes.
"""

from __future__ import annotations

import base64
import itertools
from collections import deque
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.spatial import cKDTree

from devlearn_hand_regard.attribution import VisibilityPredictor, assign, polynomial_features

if TYPE_CHECKING:
    from devlearn_hand_regard.blob_table import BlobTable

DEGREE = 2
"""Degree of the posture's polynomial features for the position regression."""
RIDGE = 1.0
"""Penalty on the regression's weights (standardised features; intercept free)."""
LABEL_LAG = 5
"""Babbling steps over which a blob's displacement is measured for its label (one decision
of the behaviour is five physics steps)."""
MOVE_PIXELS = 1.0
"""A blob that moved at least this far over :data:`LABEL_LAG` steps moved."""
STILL_PIXELS = 0.25
"""A blob that moved at most this far over :data:`LABEL_LAG` steps stayed still."""
ARM_STILL = 0.1
"""An arm whose placing joints' speed (rad/s, norm) is under this is still."""
ARM_MOVING = 2.0
"""An arm whose placing joints' speed is at least this is moving."""
HEAD_STILL = 0.5
"""A blob's motion is credited to the babbling arm only while the head turns slower than
this (rad/s): a turning head moves everything in view; a still blob is credited to the
still arm only while the head is still (:data:`ARM_STILL`)."""
MAX_JUMP = 20.0
"""Largest blob move (pixels) between the frames of a track."""
MAX_SUPPORT = 1500
"""Babbled postures kept per (hand, eye) as the model's support (a random subset)."""
SUPPORT_RADIUS = 1.2
"""A posture is inside the babbling's range for a (hand, eye) when a babbled posture that
showed that hand in that eye lies within this distance (standardised joint angles)."""
SIGMAS = 3.0
"""A blob is where the arm puts its hand when x, y and sqrt(area) are each within this many
residual standard deviations of the prediction."""
WINDOW = 4
"""Decisions of a blob's track compared with the arms' predicted motion."""
STILL_MOTION = 1.5
"""Image motion (pixels, summed over the window's steps) under which a blob, or an arm's
predicted hand, counts as still."""
MIN_COSINE = 0.3
"""A moving blob follows an arm when the cosine of its displacements over the window with
that arm's predicted ones is above this and above the other arm's."""
MAX_SIGMA = 4.0
"""Largest residual spread the place check allows (pixels of x, y and sqrt(area)): a hand is
about 12 pixels across at arm's length, so SIGMAS x 4 px is a hand's width; where babbling
was too sparse to predict a place better than that, the place says nothing and no side is
credited."""
NEIGHBOURS = 5
"""Babbled postures whose blob places make a posture's expected place."""
MIN_LABELS = 50
"""A (hand, eye) with fewer labelled blobs gets no model (that hand is never credited there)."""


def arm_joints(joints: list[list[int]]) -> list[list[int]]:
    """Per hand, the posture joints that belong to its arm (those not shared with the other
    hand's list: the head's are shared)."""
    shared = set(joints[0]) & set(joints[1])
    return [[j for j in js if j not in shared] for js in joints]


def joint_speeds(proprioception: np.ndarray, joints: list[int]) -> np.ndarray:
    """(T,) norm of the velocities of ``joints`` from (T, P) proprioception (velocities are
    the second of its six blocks, :func:`babbling.joint_state`)."""
    p = np.asarray(proprioception)
    n = p.shape[1] // 6
    return np.linalg.norm(p[:, [n + j for j in joints]], axis=1)


def _track_displacement(table: BlobTable, lag: int) -> np.ndarray:
    """(T, 2 eyes, MAX_BLOBS) distance each blob moved since ``lag`` frames before (the
    nearest blob of that eye then, within ``lag * MAX_JUMP``); NaN without one."""
    out = np.full(table.blobs.shape[:3], np.nan)
    for t in range(lag, len(table)):
        if table.episode[t] != table.episode[t - lag]:
            continue
        now, then = table.blobs[t, :, :, :2], table.blobs[t - lag, :, :, :2]
        for eye in range(2):
            d = np.linalg.norm(now[eye][:, None] - then[eye][None], axis=-1)  # (now, then)
            d = np.where(np.isnan(d), np.inf, d)
            best = d.min(axis=1)
            out[t, eye] = np.where(best <= MAX_JUMP * lag, best, np.nan)
    return out


def contingency_labels(table: BlobTable, joints: list[list[int]]) -> np.ndarray:
    """Which hand each blob of a turn-taking babbling recording is, from contingency alone.

    On frames where one arm babbles (``moving_arm``) and the other is still: when the other
    arm hangs limp (``other_arm_hangs``, one-arm babbling: its hand hangs out of view, as
    issue #39's visibility model assumed), every blob is the babbling arm's hand. When it
    holds a posture (turn-taking babbling, both hands possibly in view) and the head is
    still, a blob that moved over the last :data:`LABEL_LAG` steps is the babbling arm's
    hand, and a blob that stayed still while that arm moved fast is the still arm's hand.
    Everything else is left unlabelled. No segmentation is read.

    Args:
        table: The recording's blobs.
        joints: Per hand the posture joints (its arm's, then the head's).
    Returns:
        (T, 2 eyes, MAX_BLOBS) int8: 0 left, 1 right, -1 unlabelled.
    """
    arms = arm_joints(joints)
    head = sorted(set(joints[0]) & set(joints[1]))
    speed = np.stack([joint_speeds(table.proprioception, a) for a in arms], axis=1)  # (T, 2)
    head_speed = joint_speeds(table.proprioception, head) if head else np.zeros(len(table))
    moved = _track_displacement(table, LABEL_LAG)
    labels = np.full(moved.shape, -1, np.int8)
    for t in range(len(table)):
        m = int(table.moving_arm[t])
        if m < 0 or speed[t, 1 - m] >= ARM_STILL:
            continue
        if table.other_arm_hangs:  # the other hand hangs limp out of view: every blob is m's
            labels[t][np.isfinite(table.blobs[t, :, :, 0])] = m
            continue
        if head_speed[t] >= HEAD_STILL:
            continue
        d = moved[t]
        labels[t][d >= MOVE_PIXELS] = m
        if speed[t, m] >= ARM_MOVING and head_speed[t] < ARM_STILL:
            labels[t][d <= STILL_PIXELS] = 1 - m
    return labels


def fit_contingency_model(
    tables: list[BlobTable],
    joints: list[list[int]],
    seed: int = 0,
    ridge: float = RIDGE,
    degree: int = DEGREE,
) -> dict[str, Any]:
    """Learn where each arm's posture puts its hand in each eye, from contingency labels.

    Args:
        tables: Turn-taking (or one-arm) babbling recordings' blobs, ``moving_arm`` set.
        joints: Per hand the proprioception indices of its posture (the visibility model's
            ``joints``: the arm's shoulder and elbow, the head's moving joints).
        seed: Of the support's random subset.
        ridge: Of the regression.
        degree: Of :func:`attribution.polynomial_features`.
    Returns:
        ``joints``, ``degree``, per hand ``mean``/``scale`` (standardisation of its posture),
        per (hand, eye) ``weights`` (F, 3) [x, y, sqrt(area)], ``sigma`` (3,), ``support``
        (N, k) standardised postures, ``labels`` (count); ``None`` entries where a (hand, eye)
        had fewer than :data:`MIN_LABELS` labelled blobs; ``label_counts``.
    """
    rng = np.random.default_rng(seed)
    postures, targets, eyes, hands, episodes = [], [], [], [], []
    unseen: list[np.ndarray] = []  # (T, 2 hands, 2 eyes) the hand surely out of that eye
    for number, table in enumerate(tables):
        labels = contingency_labels(table, joints)
        frame, seen_by, slot = np.nonzero(labels >= 0)
        blob = table.blobs[frame, seen_by, slot]
        postures.append(table.proprioception[frame])
        targets.append(np.c_[blob[:, :2], np.sqrt(blob[:, 2])])
        eyes.append(seen_by)
        hands.append(labels[frame, seen_by, slot])
        episodes.append(table.episode[frame] * len(tables) + number)  # unique across tables
        unseen.append(_unseen(table, joints))
    proprioception = np.concatenate(postures).astype(float)
    target = np.concatenate(targets).astype(float)
    eye_of, hand_of = np.concatenate(eyes), np.concatenate(hands)
    episode_of = np.concatenate(episodes)
    all_postures = np.concatenate([t.proprioception for t in tables]).astype(float)
    out_of_view = np.concatenate(unseen)
    model: dict[str, Any] = {
        "joints": [list(map(int, j)) for j in joints],
        "degree": degree,
        "mean": [],
        "scale": [],
        "pairs": [[None, None], [None, None]],
        "unseen": [[None, None], [None, None]],
        "label_counts": [[0, 0], [0, 0]],
    }
    for hand in range(2):
        x = proprioception[:, joints[hand]]
        mean, scale = x.mean(axis=0), np.maximum(x.std(axis=0), 1e-6)
        model["mean"].append(np.round(mean, 5).tolist())
        model["scale"].append(np.round(scale, 5).tolist())
        for eye in range(2):
            rows = (hand_of == hand) & (eye_of == eye)
            model["label_counts"][hand][eye] = int(rows.sum())
            if rows.sum() < MIN_LABELS:
                continue
            z = (x[rows] - mean) / scale
            features = polynomial_features(z, degree)
            penalty = np.full(features.shape[1], ridge)
            penalty[0] = 0.0
            weights = np.linalg.solve(
                features.T @ features + np.diag(penalty), features.T @ target[rows]
            )
            keep = rng.permutation(len(z))[:MAX_SUPPORT]
            support, place = np.round(z[keep], 3), np.round(target[rows][keep], 2)
            # the neighbours' spread: the places of odd episodes' postures predicted from
            # the even episodes' (consecutive frames of one episode are near copies)
            odd = episode_of[rows][keep] % 2 == 1
            even_tree = cKDTree(support[~odd]) if (~odd).any() else cKDTree(support)
            residual = place[odd] - _neighbour_mean(even_tree, place[~odd], support[odd])
            residual = residual[np.isfinite(residual).all(axis=1)]
            if len(residual) < MIN_LABELS // 5:
                continue
            sigma = 1.4826 * np.median(np.abs(residual - np.median(residual, 0)), axis=0)
            model["pairs"][hand][eye] = {
                "weights": np.round(weights, 5).tolist(),
                "sigma": np.round(np.maximum(sigma, 0.5), 4).tolist(),
                "support": pack(support),
                "place": pack(place),
                "labels": int(rows.sum()),
            }
        for eye in range(2):  # where babbling showed this hand out of this eye
            away = (all_postures[out_of_view[:, hand, eye]][:, joints[hand]] - mean) / scale
            keep = rng.permutation(len(away))[:MAX_SUPPORT]
            model["unseen"][hand][eye] = pack(away[keep])
    return model


def pack(array: np.ndarray) -> dict[str, Any]:
    """A float array as JSON in little space: its shape and its float16 bytes in base64
    (postures to 0.01 standard deviation, places to 0.06 pixel: below what the rule resolves)."""
    array = np.asarray(array, dtype="<f2")
    return {"shape": list(array.shape), "float16": base64.b64encode(array.tobytes()).decode()}


def unpack(packed: dict[str, Any]) -> np.ndarray:
    """:func:`pack`'s array, as float64."""
    raw = np.frombuffer(base64.b64decode(packed["float16"]), dtype="<f2")
    return raw.reshape(packed["shape"]).astype(float)


def _unseen(table: BlobTable, joints: list[list[int]]) -> np.ndarray:
    """(T, 2 hands, 2 eyes) frames of one-arm babbling (the other arm hanging limp) where a
    hand was surely out of an eye: the babbling arm's where that eye saw no blob, the
    hanging arm's in both eyes while it was still."""
    out = np.zeros((len(table), 2, 2), dtype=bool)
    if not table.other_arm_hangs:
        return out
    speed = np.stack([joint_speeds(table.proprioception, a) for a in arm_joints(joints)], 1)
    blobless = ~np.isfinite(table.blobs[:, :, :, 0]).any(axis=2)  # (T, 2 eyes)
    for hand in range(2):
        babbling = table.moving_arm == hand
        out[:, hand] = babbling[:, None] & blobless
        hanging = (table.moving_arm == 1 - hand) & (speed[:, hand] < ARM_STILL)
        out[hanging, hand] = True
    return out


def _neighbour_mean(tree: cKDTree, place: np.ndarray, z: np.ndarray) -> np.ndarray:
    """(N, 3) inverse-distance weighted mean of the places of the :data:`NEIGHBOURS` babbled
    postures nearest each of (N, k) postures ``z`` within :data:`SUPPORT_RADIUS` (NaN rows
    where none is)."""
    distance, index = tree.query(z, k=NEIGHBOURS, distance_upper_bound=SUPPORT_RADIUS)
    found = np.isfinite(distance)
    weight = np.where(found, 1.0 / (distance + 0.05), 0.0)
    safe = np.where(found, index, 0)
    total = weight.sum(axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.einsum("nk,nkc->nc", weight, place[safe]) / total


class ContingencyModel:
    """:func:`fit_contingency_model`'s model with arrays and search trees built once."""

    def __init__(self, model: dict[str, Any]) -> None:
        self.degree = int(model["degree"])
        self.joints = [np.asarray(j, dtype=np.intp) for j in model["joints"]]
        self.mean = [np.asarray(m, dtype=float) for m in model["mean"]]
        self.scale = [np.asarray(s, dtype=float) for s in model["scale"]]
        self.weights: list[list[np.ndarray | None]] = [[None, None], [None, None]]
        self.sigma: list[list[np.ndarray | None]] = [[None, None], [None, None]]
        self.trees: list[list[cKDTree | None]] = [[None, None], [None, None]]
        self.places: list[list[np.ndarray | None]] = [[None, None], [None, None]]
        self.unseen: list[list[cKDTree | None]] = [[None, None], [None, None]]
        for hand, eye in itertools.product(range(2), range(2)):
            away = model["unseen"][hand][eye]
            if away:
                self.unseen[hand][eye] = cKDTree(unpack(away))
            pair = model["pairs"][hand][eye]
            if pair:
                self.weights[hand][eye] = np.asarray(pair["weights"], dtype=float)
                self.sigma[hand][eye] = np.asarray(pair["sigma"], dtype=float)
                self.trees[hand][eye] = cKDTree(unpack(pair["support"]))
                self.places[hand][eye] = unpack(pair["place"])

    def standardised(self, proprioception: np.ndarray) -> list[np.ndarray]:
        """Per hand its (k,) standardised posture."""
        p = np.asarray(proprioception, dtype=float)
        return [(p[self.joints[h]] - self.mean[h]) / self.scale[h] for h in range(2)]

    def out_of_view(self, z: list[np.ndarray]) -> np.ndarray:
        """(2 hands, 2 eyes) bool: babbling showed this posture with the hand out of that eye
        (a posture within :data:`SUPPORT_RADIUS` of one) and never in it (none of the
        postures that showed it there within twice that: a hand at the image's edge is often
        too cut to be a blob, so "not seen" is weaker evidence than "seen")."""
        out = np.zeros((2, 2), dtype=bool)
        for hand, eye in itertools.product(range(2), range(2)):
            away, seen = self.unseen[hand][eye], self.trees[hand][eye]
            if away is None:
                continue
            near_away = np.isfinite(away.query(z[hand], distance_upper_bound=SUPPORT_RADIUS)[0])
            near_seen = seen is not None and np.isfinite(
                seen.query(z[hand], distance_upper_bound=2 * SUPPORT_RADIUS)[0]
            )
            out[hand, eye] = bool(near_away and not near_seen)
        return out

    def predict(self, z: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Where each hand should show in each eye, and whether the posture is babbled.

        Args:
            z: :meth:`standardised` postures.
        Returns:
            prediction: (2 hands, 2 eyes, 3) [x, y, sqrt(area)] from the smooth regression
                (its differences are the arm's predicted image motion; NaN without a model).
            place: (2 hands, 2 eyes, 3) the same from the nearest babbled postures (the
                place check's; NaN where none is within :data:`SUPPORT_RADIUS`).
            supported: (2 hands, 2 eyes) bool, a babbled posture that showed that hand in
                that eye lies within :data:`SUPPORT_RADIUS`.
        """
        prediction = np.full((2, 2, 3), np.nan)
        place = np.full((2, 2, 3), np.nan)
        for hand in range(2):
            features = polynomial_features(z[hand][None], self.degree)[0]
            for eye in range(2):
                weights, tree = self.weights[hand][eye], self.trees[hand][eye]
                places = self.places[hand][eye]
                if weights is None or tree is None or places is None:
                    continue
                prediction[hand, eye] = features @ weights
                place[hand, eye] = _neighbour_mean(tree, places, z[hand][None])[0]
        return prediction, place, np.isfinite(place).all(axis=2)


class ContingencyAttribution:
    """The run-time rule: per decision, which blob (if any) each hand is, in each eye.

    Holds the last :data:`WINDOW` decisions' blobs and predictions (one episode: call
    :meth:`reset` at its start).
    """

    def __init__(
        self,
        model: dict[str, Any] | ContingencyModel,
        visibility_model: dict[str, Any] | None = None,
    ) -> None:
        self.model = model if isinstance(model, ContingencyModel) else ContingencyModel(model)
        self.visibility = VisibilityPredictor(visibility_model) if visibility_model else None
        self.history: deque[tuple[np.ndarray, np.ndarray]] = deque(maxlen=WINDOW + 1)

    def reset(self) -> None:
        """A new episode: forget the tracks."""
        self.history.clear()

    def step(self, blobs: np.ndarray, proprioception: np.ndarray) -> np.ndarray:
        """Credit this decision's blobs.

        Args:
            blobs: (2 eyes, B, 3) [x, y, area] in pixels, NaN rows where no blob.
            proprioception: (P,) this decision's proprioception.
        Returns:
            (2 eyes, B) int: the hand credited with each blob (0 left, 1 right, -1 none).
        """
        blobs = np.asarray(blobs, dtype=float)
        z = self.model.standardised(proprioception)
        prediction, place, supported = self.model.predict(z)
        away = self.model.out_of_view(z)
        # issue #39's posture-only evidence, when the detector has it: P(eye sees hand)
        likelihood = self.visibility(proprioception) if self.visibility is not None else None
        self.history.append((blobs[:, :, :2].copy(), prediction[:, :, :2].copy()))
        out = np.full(blobs.shape[:2], -1, dtype=int)
        for eye in range(2):
            present = np.flatnonzero(np.isfinite(blobs[eye, :, 0]))
            if not len(present):
                continue
            consistent = np.zeros((len(present), 2), dtype=bool)
            cost = np.zeros((len(present), 2))
            for row, b in enumerate(present):
                where, cost[row] = self._in_place(
                    eye, blobs[eye, b], place[:, eye], supported[:, eye]
                )
                if where.any():
                    consistent[row] = where & self._moves_with(eye, int(b))
            for row, hand in _agreed(consistent, cost).items():
                # the other hand must be accounted for: known out of this eye, or placed
                # by its model (in the babbled range) where it could be told apart
                accounted = away[1 - hand, eye] or supported[1 - hand, eye]
                agrees = likelihood is None or hand in assign(likelihood[eye], len(present))
                if accounted and agrees:
                    out[eye, present[row]] = hand
        return out

    def _in_place(
        self, eye: int, blob: np.ndarray, prediction: np.ndarray, supported: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Per hand: the posture is babbled and the blob's x, y and sqrt(area) are each
        within :data:`SIGMAS` residual spreads of where that arm puts its hand ((2,) bool);
        and the largest of those three distances in spreads ((2,), inf without a model)."""
        observed = np.array([blob[0], blob[1], np.sqrt(blob[2])])
        inside = np.zeros(2, dtype=bool)
        distance = np.full(2, np.inf)
        for hand in range(2):
            sigma = self.model.sigma[hand][eye]
            if sigma is not None:
                sigma = np.minimum(sigma, MAX_SIGMA)
                distance[hand] = float(np.max(np.abs(observed - prediction[hand]) / sigma))
                inside[hand] = bool(supported[hand] and distance[hand] <= SIGMAS)
        return inside, distance

    def _moves_with(self, eye: int, b: int) -> np.ndarray:
        """(2 hands,) the blob's track over the window follows that arm (see the module)."""
        track = self._track(eye, b)
        if track is None:  # the first decision of an episode or a new blob: no evidence
            return np.zeros(2, dtype=bool)
        positions, predicted = track  # (k + 1, 2), (k + 1, 2 hands, 2)
        moves = np.diff(positions, axis=0)  # (k, 2)
        expected = np.diff(predicted, axis=0)  # (k, 2 hands, 2)
        motion = float(np.linalg.norm(moves, axis=1).sum())
        arm_motion = np.linalg.norm(expected, axis=2).sum(axis=0)  # (2 hands,)
        # how well the blob's displacements follow each arm's predicted ones: their cosine
        # over the window's steps (x and y together), 1 when they move alike
        flat, predicted = moves.ravel(), expected.transpose(1, 0, 2).reshape(2, -1)
        norms = np.linalg.norm(flat) * np.linalg.norm(predicted, axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            cosine = np.where(norms > 0, predicted @ flat / norms, 0.0)
        cosine = np.where(np.isfinite(cosine), cosine, -1.0)
        out = np.zeros(2, dtype=bool)
        for hand in range(2):
            if motion < STILL_MOTION:
                out[hand] = arm_motion[hand] < STILL_MOTION
            else:
                out[hand] = cosine[hand] > MIN_COSINE and cosine[hand] > cosine[1 - hand]
        return out

    def _track(self, eye: int, b: int) -> tuple[np.ndarray, np.ndarray] | None:
        """The blob's positions back through the window (nearest blob within
        :data:`MAX_JUMP` each decision) and the hands' predicted positions at those
        decisions; None when the track is shorter than two decisions."""
        frames = list(self.history)
        position = frames[-1][0][eye, b]
        positions, predicted = [position], [frames[-1][1][:, eye]]
        for blobs, prediction in reversed(frames[:-1]):
            d = np.linalg.norm(blobs[eye] - position, axis=1)
            d = np.where(np.isnan(d), np.inf, d)
            if not np.isfinite(d).any() or d.min() > MAX_JUMP:
                break
            position = blobs[eye, int(np.argmin(d))]
            positions.append(position)
            predicted.append(prediction[:, eye])
        if len(positions) < 3:
            return None
        return np.asarray(positions[::-1]), np.asarray(predicted[::-1])


def _agreed(consistent: np.ndarray, cost: np.ndarray | None = None) -> dict[int, int]:
    """The blob -> hand credits the evidence agrees on.

    Args:
        consistent: (blobs, 2 hands) bool, the evidence allows that hand for that blob.
        cost: (blobs, 2 hands) how far each blob is from where each arm puts its hand (in
            residual spreads); chooses the pairing when two hands are surely in view but
            which blob is which is open. None: the first pairing.
    Returns:
        {blob row: hand}: the hands present in every matching (one hand per blob, one blob
        per hand) of the largest size, each with its blob in the cheapest such matching.
        Where the evidence leaves a choice of hand (one blob either hand's), no side.
    """
    rows = consistent.shape[0]
    matchings: list[dict[int, int]] = []
    for hands in itertools.product([-1, 0, 1], repeat=rows):
        used = [h for h in hands if h >= 0]
        if len(used) != len(set(used)):
            continue
        if all(h < 0 or consistent[r, h] for r, h in enumerate(hands)):
            matchings.append({r: h for r, h in enumerate(hands) if h >= 0})
    best = max(len(m) for m in matchings)
    if not best:
        return {}
    largest = [m for m in matchings if len(m) == best]
    sure = set.intersection(*[set(m.values()) for m in largest])
    if cost is None:
        chosen = largest[0]
    else:
        chosen = min(largest, key=lambda m: sum(float(cost[r, h]) for r, h in m.items()))
    return {r: h for r, h in chosen.items() if h in sure}
