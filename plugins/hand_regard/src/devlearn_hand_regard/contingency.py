"""Which hand is it, from where the body says each hand is and which blob moves with which arm
(issue #58; ``hand_attribution=contingency``).

Issue #39's rule gave a blob to the hand whose arm's posture made it likelier in view; its
policies learned postures one-arm babbling never showed (the left hand across the midline, in
the right eye), where both hands were rated near zero and the larger near-zero took the blob:
an absent right hand was credited on 8-95% of steps. Issue #58's first contingency rule learned
each arm's hand place from babbled postures (nearest neighbours); it was 5-20 px off between
babbled postures, so on issue #39's ``reach_t4`` seed 1 the left hand low in the right eye's
corner fell within the right arm's coarse place and was credited to the right (5% of steps),
and it credited true hands seldom (recall 1-4%).

This rule asks the body (:mod:`~devlearn_hand_regard.contingency_body`): every joint of the
seated infant is sensed, so each hand's centre and depth before each eye follow from the
proprioception by forward kinematics, wherever the policy puts its arms (crossings included).
Babbling, without the segmentation, calibrates how far from that centre a hand's blob lies
(:func:`fit_contingency_model`: contingency labels, :func:`contingency_labels`; the blob of a
hand at depth d lies within ``pixels + radius * focal / d`` of its projected centre: the hand
looks bigger near the eye, is cut by the image's edge, and the babbling's image lags its
proprioception by a step). Per decision and eye (:meth:`ContingencyAttribution.step`):

1. **where**: a hand *can* be a blob within its reach; it *cannot* be a blob farther than
   :data:`MARGIN` reaches (or behind the eye);
2. **which arm it moves with** (the contingency): over the last :data:`WINDOW` decisions, a
   blob that moved must move with the credited arm's projected hand (cosine above
   :data:`MIN_COSINE`; optional, :data:`USE_MOTION`);
3. a blob is credited to a hand only when that hand can be it and the other hand cannot
   (both can: the evidence does not tell them apart, no side);
4. **two hands, two blobs** (:data:`PAIR_BLOBS`): where an eye shows two blobs, each within
   reach of exactly one hand and of different hands, each is its hand's (when it moves with
   that arm), even though the other hand is nearer than the :data:`MARGIN` allows: both
   hands are in view beside each other, the case rule 3 alone credited to no side (issue
   #58's pilot, seed 3: the detector 0.09-0.27 below ``pixels``).

Validation and the adversarial replay of every published policy:
``python -m devlearn_hand_regard.contingency_check`` (``results/hand_regard/i58_attribution``).
"""

from __future__ import annotations

from collections import deque
from typing import TYPE_CHECKING, Any

import numpy as np

from devlearn_hand_regard.contingency_body import BodySchema

if TYPE_CHECKING:
    from devlearn_hand_regard.blob_table import BlobTable

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
REACH_PIXELS = 3.0
"""Part of a hand's reach that does not shrink with depth (pixels: centroid jitter)."""
REACH_QUANTILE = 95.0
"""The reach's radius is :data:`REACH_FACTOR` times this percentile of the labelled blobs'
(distance - REACH_PIXELS) * depth / focal. Not the 99th: about 1% of contingency labels name
the wrong hand (99.1% right on the training babbling), and from a short babbling (3,000
steps) the 99th percentile was a mislabel's (0.39 m, a reach covering the view)."""
REACH_FACTOR = 1.2
"""Widens the :data:`REACH_QUANTILE` percentile to hold nearly every true blob (on the
training babbling 1.2 x the 95th percentile is 0.055 m, the 99th 0.054 m)."""
MARGIN = 1.5
"""A hand cannot be a blob farther than this many of its reaches from its projected centre."""
WINDOW = 4
"""Decisions of a blob's track compared with the arms' projected motion."""
STILL_MOTION = 3.0
"""A blob that moved less than this (pixels, summed over the window's steps) says nothing
about which arm moves it."""
MIN_COSINE = 0.0
"""A blob that moved is credited to an arm only when the cosine of its displacements with
that arm's projected hand's is above this."""
USE_MOTION = True
"""Require the motion agreement (item 2 of the rule) for a credit."""
PAIR_BLOBS = True
"""Credit two blobs of an eye to the two hands when each blob is within reach of one hand
only (item 4 of the rule). On every published policy's replayed frames it credited no absent
hand and raised recall where both hands are in view (issue #39's ``reach_t4`` seed 3: 0.52 to
0.83; the #58 pilot's seed 3: 0.65 to 0.78; ``results/hand_regard/i58_attribution``). Runs
saved before it (config key ``contingency_pairs`` absent) attribute without it."""
MIN_LABELS = 50
"""Fewer labelled babbled blobs than this: no calibration (the fit fails and says so)."""
MODEL_VERSION = 2
"""Version of :func:`fit_contingency_model`'s dict (1: issue #58's nearest-posture model,
no longer read)."""


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
    schema: dict[str, Any],
    quantile: float = REACH_QUANTILE,
) -> dict[str, Any]:
    """Calibrate how far a hand's blob lies from where the body says the hand is.

    Args:
        tables: Babbling recordings' blobs (``moving_arm`` set: one-arm or turn-taking).
        joints: Per hand the posture joints (its arm's shoulder and elbow, the head's), for
            the contingency labels' arm speeds.
        schema: :func:`contingency_body.body_schema` of the infant that babbled.
        quantile: :data:`REACH_QUANTILE`.
    Returns:
        ``version``, ``body`` (the schema), ``reach`` (``pixels``, ``radius`` in m: a hand's
        blob lies within ``pixels + radius * focal / depth`` of its projected centre),
        ``label_counts`` (2 hands, 2 eyes), ``distance_quantiles`` (px, 50/90/99).
    Raises:
        ValueError: Fewer than :data:`MIN_LABELS` labelled blobs.
    """
    body = BodySchema(schema)
    distance, scale = [], []
    counts = np.zeros((2, 2), dtype=int)
    for table in tables:
        labels = contingency_labels(table, joints)
        for t in np.unique(np.nonzero(labels >= 0)[0]):
            projected = body.project(table.proprioception[t])
            for eye, slot in zip(*np.nonzero(labels[t] >= 0)):
                hand = int(labels[t, eye, slot])
                x, y, depth = projected[hand, eye]
                counts[hand, eye] += 1
                if depth <= 0:
                    continue
                bx, by = table.blobs[t, eye, slot, :2]
                distance.append(float(np.hypot(x - bx, y - by)))
                scale.append(body.eyes[eye][3] / depth)
    if len(distance) < MIN_LABELS:
        raise ValueError(
            f"{len(distance)} labelled blobs from babbling, at least {MIN_LABELS} needed: "
            "babble longer (one-arm babbling labels every blob of a still other arm)"
        )
    d, s = np.asarray(distance), np.asarray(scale)
    radius = REACH_FACTOR * float(np.percentile(np.maximum(d - REACH_PIXELS, 0.0) / s, quantile))
    return {
        "version": MODEL_VERSION,
        "body": schema,
        "reach": {"pixels": REACH_PIXELS, "radius": round(radius, 5)},
        "label_counts": counts.tolist(),
        "distance_quantiles": np.round(np.percentile(d, [50, 90, 99]), 2).tolist(),
        "radius_quantiles": np.round(
            np.percentile(np.maximum(d - REACH_PIXELS, 0.0) / s, [25, 50, 75, 90, 95, 99]), 4
        ).tolist(),
    }


def check_contingency_model(model: dict[str, Any]) -> None:
    """Raise ValueError unless ``model`` is :func:`fit_contingency_model`'s (this version)
    and places both hands at a finite depth for a resting posture."""
    if model.get("version") != MODEL_VERSION:
        raise ValueError(
            f"contingency_model version {model.get('version')!r}; this rule reads version "
            f"{MODEL_VERSION} (refit: python -m devlearn_hand_regard.contingency_check fit)"
        )
    reach = model["reach"]
    body = BodySchema(model["body"])
    projected = body.project(np.zeros(body.angles))
    if not (np.isfinite(projected[:, :, 2]).all() and float(reach["radius"]) > 0):
        raise ValueError("contingency_model places no hand (its body schema is damaged)")


class ContingencyAttribution:
    """The run-time rule: per decision, which blob (if any) each hand is, in each eye.

    Holds the last :data:`WINDOW` decisions' blobs and projected hands (one episode: call
    :meth:`reset` at its start).

    Args:
        model: :func:`fit_contingency_model`'s dict.
        visibility_model: Unused (issue #39's posture-only evidence; kept so callers need
            not change).
        margin: :data:`MARGIN`.
        use_motion: :data:`USE_MOTION`.
        pair_blobs: :data:`PAIR_BLOBS`.
    """

    def __init__(
        self,
        model: dict[str, Any],
        visibility_model: dict[str, Any] | None = None,
        margin: float = MARGIN,
        use_motion: bool = USE_MOTION,
        pair_blobs: bool = PAIR_BLOBS,
    ) -> None:
        check_contingency_model(model)
        self.body = BodySchema(model["body"])
        self.pixels = float(model["reach"]["pixels"])
        self.radius = float(model["reach"]["radius"])
        self.margin = margin
        self.use_motion = use_motion
        self.pair_blobs = pair_blobs
        self.history: deque[tuple[np.ndarray, np.ndarray]] = deque(maxlen=WINDOW + 1)

    def reset(self) -> None:
        """A new episode: forget the tracks."""
        self.history.clear()

    def reach(self, projected: np.ndarray) -> np.ndarray:
        """(2 hands, 2 eyes) pixels from its projected centre within which a hand's blob
        lies (inf for a hand behind the eye: never credited, never ruled out there)."""
        depth = projected[:, :, 2]
        focal = np.array([e[3] for e in self.body.eyes])[None, :]
        with np.errstate(divide="ignore"):
            return np.where(depth > 0, self.pixels + self.radius * focal / depth, np.inf)

    def step(self, blobs: np.ndarray, proprioception: np.ndarray) -> np.ndarray:
        """Credit this decision's blobs.

        Args:
            blobs: (2 eyes, B, 3) [x, y, area] in pixels, NaN rows where no blob.
            proprioception: (P,) this decision's proprioception.
        Returns:
            (2 eyes, B) int: the hand credited with each blob (0 left, 1 right, -1 none).
        """
        blobs = np.asarray(blobs, dtype=float)
        projected = self.body.project(proprioception)  # (2 hands, 2 eyes, 3)
        reach = self.reach(projected)
        self.history.append((blobs[:, :, :2].copy(), projected[:, :, :2].copy()))
        out = np.full(blobs.shape[:2], -1, dtype=int)
        for eye in range(2):
            present = np.flatnonzero(np.isfinite(blobs[eye, :, 0]))
            behind = projected[:, eye, 2] <= 0
            # (blobs, 2 hands) distance from each hand's projected centre, in its reaches
            relative = np.full((len(present), 2), np.inf)
            for row, b in enumerate(present):
                distance = np.linalg.norm(projected[:, eye, :2] - blobs[eye, b, :2], axis=1)
                relative[row] = np.where(behind, np.inf, distance / reach[:, eye])
            can, cannot = relative <= 1.0, relative > self.margin
            for row, b in enumerate(present):
                for hand in range(2):
                    if can[row, hand] and cannot[row, 1 - hand] and self._agrees(eye, int(b), hand):
                        out[eye, b] = hand
            if self.pair_blobs and len(present) == 2:
                self._pair(out[eye], eye, present, can)
        return out

    def _pair(self, credited: np.ndarray, eye: int, present: np.ndarray, can: np.ndarray) -> None:
        """Rule 4: two blobs, each within reach of one hand only, and of different hands, are
        those hands' (each moving with its arm); ``credited`` (B,) is updated in place."""
        if can.sum(axis=1).tolist() != [1, 1]:
            return
        hands = [int(np.argmax(row)) for row in can]
        if hands[0] == hands[1]:
            return
        if all(self._agrees(eye, int(b), h) for b, h in zip(present, hands)):
            for b, h in zip(present, hands):
                credited[b] = h

    def _agrees(self, eye: int, b: int, hand: int) -> bool:
        """The motion evidence allows crediting blob ``b`` to ``hand`` (always, without it)."""
        return not self.use_motion or self._moves_with(eye, int(b), hand)

    def _moves_with(self, eye: int, b: int, hand: int) -> bool:
        """The blob's track over the window moves with ``hand``'s projected centre, or
        moved too little to say (the first decisions of an episode say nothing either)."""
        track = self._track(eye, b)
        if track is None:
            return True
        positions, projected = track  # (k + 1, 2), (k + 1, 2 hands, 2)
        moves = np.diff(positions, axis=0).ravel()
        expected = np.diff(projected[:, hand], axis=0).ravel()
        if np.linalg.norm(np.diff(positions, axis=0), axis=1).sum() < STILL_MOTION:
            return True
        norms = np.linalg.norm(moves) * np.linalg.norm(expected)
        if not np.isfinite(norms) or norms <= 0:
            return True
        return bool(moves @ expected / norms > MIN_COSINE)

    def _track(self, eye: int, b: int) -> tuple[np.ndarray, np.ndarray] | None:
        """The blob's positions back through the window (nearest blob within
        :data:`MAX_JUMP` each decision) and the hands' projected centres at those
        decisions; None when the track is shorter than three decisions."""
        frames = list(self.history)
        position = frames[-1][0][eye, b]
        positions, projected = [position], [frames[-1][1][:, eye]]
        for blobs, centres in reversed(frames[:-1]):
            d = np.linalg.norm(blobs[eye] - position, axis=1)
            d = np.where(np.isnan(d), np.inf, d)
            if not np.isfinite(d).any() or d.min() > MAX_JUMP:
                break
            position = blobs[eye, int(np.argmin(d))]
            positions.append(position)
            projected.append(centres[:, eye])
        if len(positions) < 3:
            return None
        return np.asarray(positions[::-1]), np.asarray(projected[::-1])
