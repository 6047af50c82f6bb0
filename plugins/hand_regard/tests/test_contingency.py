"""The contingency attribution (issue #58): labels from turn-taking babbling, the per-arm
position model with its support, and the run-time rule that credits a blob to a side only
when place and motion agree (synthetic blob tables, no rendering)."""

from __future__ import annotations

import numpy as np
import pytest
from devlearn_hand_regard.blob_table import MAX_BLOBS, BlobTable
from devlearn_hand_regard.contingency import (
    ContingencyAttribution,
    _agreed,
    contingency_labels,
    fit_contingency_model,
)

JOINTS = [[1, 2, 0], [3, 4, 0]]
"""Synthetic proprioception: angles of [head swivel, left shoulder, left elbow, right
shoulder, right elbow], then their velocities, then four blocks of zeros (the infant's
six-block layout)."""
N = 5


def hand_place(q: np.ndarray, hand: int, eye: int) -> np.ndarray:
    """[x, y, area] where a synthetic hand shows: the shoulder carries it across the image
    (the left hand to the right as its shoulder rises past 0: the crossing), the elbow up
    and down, the head's swivel shifts the view, the eyes see it 6 px apart."""
    shoulder, elbow = q[1 + 2 * hand], q[2 + 2 * hand]
    sign = 1.0 if hand == 0 else -1.0
    x = 32 + sign * 25 * shoulder - 12 * q[0] + (6 if eye == 0 else -6)
    y = 32 + 22 * elbow
    return np.array([x, y, 120.0 + 10 * hand])


def in_image(place: np.ndarray) -> bool:
    return bool(0 <= place[0] < 64 and 0 <= place[1] < 64)


def table_of(qpos: np.ndarray, moving: np.ndarray, episode: np.ndarray) -> BlobTable:
    """Blob table of a synthetic recording: every hand in an eye's image is a blob."""
    steps = len(qpos)
    qvel = np.zeros_like(qpos)
    qvel[1:] = np.diff(qpos, axis=0) / 0.005
    qvel[1:][episode[1:] != episode[:-1]] = 0.0
    proprioception = np.concatenate([qpos, qvel, np.zeros((steps, 4 * N))], axis=1)
    blobs = np.full((steps, 2, MAX_BLOBS, 3), np.nan, np.float32)
    owner = np.full((steps, 2, MAX_BLOBS), -1, np.int8)
    pixels = np.zeros((steps, 2, 2), np.int32)
    for t in range(steps):
        for eye in range(2):
            found = [(h, hand_place(qpos[t], h, eye)) for h in (1, 0)]  # larger first
            found = [(h, p) for h, p in found if in_image(p)]
            for i, (h, p) in enumerate(found):
                blobs[t, eye, i], owner[t, eye, i] = p, h
                pixels[t, eye, h] = int(p[2])
    return BlobTable(blobs, proprioception.astype(np.float32), episode, pixels, owner, moving)


def turn_babbling(episodes: int = 24, length: int = 300, seed: int = 0) -> BlobTable:
    """Both arms start anywhere; they take turns of 100 steps, one wandering smoothly while
    the other holds still; the head holds one swivel per episode."""
    rng = np.random.default_rng(seed)
    qpos = np.zeros((episodes * length, N))
    moving = np.zeros(episodes * length, np.int8)
    for e in range(episodes):
        q = np.r_[rng.uniform(-0.5, 0.5), rng.uniform(-1.2, 1.2, 4)]
        velocity = np.zeros(2)
        for k in range(length):
            arm = (k // 100 + e) % 2
            velocity = 0.9 * velocity + 0.1 * rng.normal(0, 0.06, 2)
            q[1 + 2 * arm : 3 + 2 * arm] = np.clip(
                q[1 + 2 * arm : 3 + 2 * arm] + velocity, -1.2, 1.2
            )
            qpos[e * length + k], moving[e * length + k] = q, arm
    episode = np.repeat(np.arange(episodes), length).astype(np.int32)
    return table_of(qpos, moving, episode)


@pytest.fixture(scope="module")
def model():
    return fit_contingency_model([turn_babbling()], JOINTS)


def test_labels_from_contingency_name_the_true_hand():
    table = turn_babbling(episodes=8, seed=1)
    labels = contingency_labels(table, JOINTS)
    known = labels >= 0
    assert known.sum() > 500  # both kinds of label: the moving blob and the still one
    assert (labels[known] == table.blob_hand[known]).mean() > 0.97
    assert set(np.unique(labels[known])) == {0, 1}


def test_the_model_predicts_where_each_arm_puts_its_hand(model):
    attribution = ContingencyAttribution(model)
    q = np.array([0.1, 0.4, 0.2, -0.3, -0.5])
    prediction, place, supported = attribution.model.predict(
        attribution.model.standardised(np.r_[q, np.zeros(5 * N)])
    )
    for hand in range(2):
        for eye in range(2):
            assert supported[hand, eye]
            truth = hand_place(q, hand, eye)[:2]
            np.testing.assert_allclose(prediction[hand, eye, :2], truth, atol=1.5)
            # the nearest babbled postures' place is coarser: the true blob passes its check
            inside, _ = attribution._in_place(
                eye, hand_place(q, hand, eye), place[:, eye], supported[:, eye]
            )
            assert inside[hand]
    assert not attribution.model.predict(  # far outside every babbled posture
        attribution.model.standardised(np.r_[0.1, 4.0, 4.0, -4.0, 4.0, np.zeros(5 * N)])
    )[2].any()


def play(model, qpos: np.ndarray, blobs_of) -> np.ndarray:
    """Run the rule over a synthetic episode; ``blobs_of(t, q)`` gives (2, B, 3) blobs.
    Returns (T, 2 eyes, 2 hands) credited."""
    attribution = ContingencyAttribution(model)
    steps = len(qpos)
    qvel = np.zeros_like(qpos)
    qvel[1:] = np.diff(qpos, axis=0) / 0.025
    out = np.zeros((steps, 2, 2), bool)
    for t in range(steps):
        p = np.r_[qpos[t], qvel[t], np.zeros(4 * N)]
        blobs = blobs_of(t, qpos[t])
        hands = attribution.step(blobs, p)
        for eye in range(2):
            for hand in hands[eye]:
                if hand >= 0:
                    out[t, eye, hand] = True
    return out


def blobs_of_hands(hands):
    def of(t, q):
        rows = np.full((2, MAX_BLOBS, 3), np.nan)
        for eye in range(2):
            seen = [hand_place(q, h, eye) for h in hands if in_image(hand_place(q, h, eye))]
            for i, place in enumerate(seen):
                rows[eye, i] = place
        return rows

    return of


def test_a_moving_hand_is_credited_to_its_arm_and_a_still_one_too(model):
    steps = 40
    qpos = np.tile([0.0, 0.3, 0.1, -0.2, -0.4], (steps, 1))
    qpos[:, 1] += np.linspace(0, 0.4, steps)  # the left arm moves, the right holds still
    credited = play(model, qpos, blobs_of_hands((0, 1)))
    assert credited[2:, :, 1].all()  # the still right hand, still where its arm puts it
    assert credited[12:, :, 0].all()  # the moving left hand (its first postures at the edge
    assert credited[:, :, 0].mean() > 0.6  # of the babbled range)
    assert not credited[:2].any()  # no track yet: no evidence of motion, no side


def test_a_blob_that_moves_with_the_other_arm_is_credited_to_no_side(model):
    """The fooling case of issue #39: the policy holds the right arm still where the right
    hand would show in view, and the blob there moves with the left arm. Place says right,
    motion says left: no side is credited (the visibility rule of issue #39 gave it to the
    hand likelier in view)."""
    steps = 40
    qpos = np.tile([0.0, 0.3, 0.1, 0.5, 0.3], (steps, 1))  # the hands 20 px apart
    qpos[:, 1] += 0.05 * np.sin(np.arange(steps) * np.pi / 2)  # the left arm swings

    def blobs(t, q):
        rows = np.full((2, MAX_BLOBS, 3), np.nan)
        for eye in range(2):  # at the right hand's place, moving as the left hand does
            swing = hand_place(q, 0, eye) - hand_place(qpos[0], 0, eye)
            rows[eye, 0] = hand_place(q, 1, eye) + swing
        return rows

    credited = play(model, qpos, blobs)
    assert not credited.any()
    # the same blob, held still: place and motion (both still) agree on the right hand
    still = np.tile(qpos[0], (steps, 1))
    assert play(model, still, blobs)[3:, :, 1].all()


def test_out_of_the_babbled_range_no_side_is_credited(model):
    steps = 30
    qpos = np.tile([0.0, 3.5, 3.5, -3.5, 3.5], (steps, 1))  # both arms beyond babbling
    credited = play(model, qpos, lambda t, q: np.array([[[30, 30, 120], [np.nan] * 3]] * 2))
    assert not credited.any()


def test_agreement_leaves_a_choice_uncredited():
    assert _agreed(np.array([[True, False]])) == {0: 0}
    assert _agreed(np.array([[True, True]])) == {}  # one blob, either hand: no side
    assert _agreed(np.array([[True, True], [False, True]])) == {0: 0, 1: 1}
    # both hands surely in view, which blob is which open: both credited, the cheaper pairing
    both = np.array([[True, True], [True, True]])
    assert _agreed(both, np.array([[0.5, 2.0], [2.0, 0.5]])) == {0: 0, 1: 1}
    assert _agreed(both, np.array([[2.0, 0.5], [0.5, 2.0]])) == {0: 1, 1: 0}
    assert _agreed(np.array([[False, False], [False, True]])) == {1: 1}
