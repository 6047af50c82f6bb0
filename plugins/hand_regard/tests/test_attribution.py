"""Which hand is it (issue #39): each hand's visibility learned from its own arm's posture on
one-arm babbling, and the detector attributing blobs by it (synthetic, no rendering)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from devlearn_hand_regard import HandRegard, HandRegardConfig
from devlearn_hand_regard.attribution import (
    _monomials,
    assign,
    fit_logistic,
    fit_visibility_model,
    polynomial_features,
    predict_visibility,
    visibility_labels,
)
from devlearn_hand_regard.babbling import BabblingData, mirror_signs, posture_joints
from devlearn_hand_regard.detector import DetectorParams, HandDetector
from synthetic import draw

from devlearn.testing import load_saved_config

BLOCKS = np.array([[12.0, 52.0], [32.0, 56.0], [52.0, 50.0]])
NAMES = ["head_swivel", "head_tilt", "left_shoulder_flexion", "left_elbow", "left_wrist_flexion"]
NAMES += ["right_shoulder_flexion", "right_elbow", "right_wrist_flexion"]
GROUPS = {
    "head": np.array([0, 1]),
    "left_arm": np.array([2, 3, 4]),
    "right_arm": np.array([5, 6, 7]),
}
RAISED = 0.6
"""A synthetic hand is in view when its arm's shoulder angle is above this."""


def one_arm_babbling(
    steps: int = 4000,
    episode: int = 500,
    seed: int = 0,
    right_reach: float = 1.0,
    turn: bool = False,
) -> tuple[BabblingData, np.ndarray]:
    """Proprioception of 8 joints ([qpos, 5 x zeros] as the infant's layout), one arm
    babbling per episode (left first) while the other hangs at -0.5; a hand is in view (of
    both eyes) when its shoulder is raised above :data:`RAISED`, whatever its elbow or wrist
    (``turn``: and the head turned towards it, swivel > 0 for the left hand, < 0 for the
    right). The head's tilt is held (constant); the swivel wanders. ``right_reach``: the
    right shoulder's highest babbled angle (below RAISED: the right hand is never seen)."""
    rng = np.random.default_rng(seed)
    qpos = np.zeros((steps, 8))
    qpos[:, 0] = rng.uniform(-0.5, 0.5, steps)
    qpos[:, 1] = 0.4  # held
    moving = (np.arange(steps) // episode) % 2
    for hand, joints in enumerate((GROUPS["left_arm"], GROUPS["right_arm"])):
        babbling = moving == hand
        qpos[:, joints] = -0.5
        qpos[np.ix_(babbling, joints)] = rng.uniform(-1, 1, (int(babbling.sum()), 3))
    qpos[:, 5] = np.minimum(qpos[:, 5], right_reach)
    seen = np.zeros((steps, 2), bool)
    for shoulder, side in ((2, 1.0), (5, -1.0)):
        seen |= ((qpos[:, shoulder] > RAISED) & (side * qpos[:, 0] > 0 if turn else True))[:, None]
    data = BabblingData(
        eyes=np.zeros((steps, 2, 1, 1, 3), np.uint8),
        proprioception=np.c_[qpos, np.zeros((steps, 40))].astype(np.float32),
        actions=np.zeros((steps, 8), np.float32),
        arm_speed=np.zeros((steps, 2), np.float32),
        episode=np.arange(steps) // episode,
        moving_arm=moving,
        posture_joints=posture_joints(NAMES, GROUPS),
        posture_mirror=mirror_signs(NAMES, posture_joints(NAMES, GROUPS)[0]),
    )
    return data, seen


def posture(left: float, right: float, swivel: float = 0.0) -> np.ndarray:
    """(48,) proprioception with the shoulders at ``left`` and ``right``, elbows and wrists 0."""
    qpos = np.array([swivel, 0.4, left, 0.0, 0.0, right, 0.0, 0.0])
    return np.r_[qpos, np.zeros(40)]


@pytest.fixture(scope="module")
def model():
    return fit_visibility_model([one_arm_babbling()])


def test_posture_joints_are_each_arms_shoulder_and_elbow_and_the_head():
    assert posture_joints(NAMES, GROUPS) == [[2, 3, 0, 1], [5, 6, 0, 1]]
    # in the mirror the head's turn reverses, its nod and the arms' angles do not
    assert mirror_signs(NAMES, [2, 3, 0, 1]) == [1.0, 1.0, -1.0, 1.0]


def test_polynomial_features_and_a_logistic_fit():
    x = np.array([[1.0, 2.0], [3.0, -1.0]])
    np.testing.assert_array_equal(
        polynomial_features(x, 2), [[1, 1, 2, 1, 2, 4], [1, 3, -1, 9, -3, 1]]
    )
    assert polynomial_features(np.zeros((3, 5))).shape == (3, 56)  # degree 3, five angles
    rng = np.random.default_rng(0)
    z = rng.uniform(-1, 1, (500, 1))
    labels = (z[:, 0] ** 2 < 0.25).astype(float)  # a band: needs the square term
    weights = fit_logistic(polynomial_features(z, 2), labels, ridge=0.1)
    p = 1 / (1 + np.exp(-polynomial_features(np.array([[0.0], [0.9]]), 2) @ weights))
    assert p[0] > 0.9 and p[1] < 0.1


def test_labels_come_from_the_arm_that_babbled_alone():
    data, seen = one_arm_babbling(1000)
    labels, usable = visibility_labels(data, seen)
    assert usable.all()
    left_episode = data.moving_arm == 0
    np.testing.assert_array_equal(labels[left_episode, :, 0], seen[left_episode])
    assert not labels[left_episode, :, 1].any()  # the still arm's hand is never in view
    data.moving_arm[:] = -1  # both arms babbling: a blob could be either hand
    assert not visibility_labels(data, seen)[1].any()
    assert fit_visibility_model([(data, seen)]) == {}


def test_visibility_model_follows_each_arms_own_posture(model):
    # the held head tilt (joint 1) is left out; the wrists are not inputs
    assert model["joints"] == [[2, 3, 0], [5, 6, 0]]
    assert min(model["seen_frames"]) >= 20
    left_up = predict_visibility(model, posture(0.9, -0.5))
    assert np.all(left_up[:, 0] > 0.9) and np.all(left_up[:, 1] < 0.1)
    right_up = predict_visibility(model, posture(-0.5, 0.9))
    assert np.all(right_up[:, 1] > 0.9) and np.all(right_up[:, 0] < 0.1)
    both = predict_visibility(model, posture(0.9, 0.9))
    assert np.all(both > 0.9)
    # a posture beyond every babbled angle is read at the babbling range's edge, where the
    # quadratic features cannot run away
    beyond = predict_visibility(model, posture(9.0, -9.0))
    assert np.all(beyond[:, 0] > 0.9) and np.all(beyond[:, 1] < 0.1)


def test_each_hand_also_learns_from_the_other_arm_in_the_mirror():
    """A hand is seen with its arm raised and the head turned towards it. The right arm
    raised its hand into view only in 30 frames, the left one often: seen in the mirror (same
    angles, head turn reversed) the left arm's frames teach the right hand's model where the
    head must turn; a mirror that kept the turn's sign would teach it the wrong way."""
    data, seen = one_arm_babbling(right_reach=0.3, turn=True)
    few = np.flatnonzero(data.moving_arm == 1)[:30]  # a few raised right-arm frames
    data.proprioception[few, 5], data.proprioception[few, 0] = 0.9, -0.4
    seen[few] = True
    turned_right, turned_left = posture(-0.5, 0.8, swivel=-0.3), posture(-0.5, 0.8, swivel=0.3)
    mirrored = fit_visibility_model([(data, seen)])
    assert np.all(predict_visibility(mirrored, turned_right)[:, 1] > 0.8)
    assert np.all(predict_visibility(mirrored, turned_left)[:, 1] < 0.2)
    data.posture_mirror = [1.0] * 4  # a wrong mirror: the head's turn not reversed
    wrong = fit_visibility_model([(data, seen)])
    assert np.all(predict_visibility(wrong, turned_left)[:, 1] > 0.5)


def test_assign_names_the_likeliest_hands():
    assert assign(np.array([0.9, 0.2]), 0) == []
    assert assign(np.array([0.9, 0.2]), 1) == [0]
    assert assign(np.array([0.1, 0.3]), 1) == [1]  # a blob is a hand: the likelier one
    assert assign(np.array([0.9, 0.8]), 2) == [0, 1]
    assert assign(np.array([0.9, 0.3]), 2) == [0]  # one hand in two pieces


def test_a_blob_goes_to_the_raised_arms_hand_wherever_it_is(synthetic_params, model):
    """The blob sits where the right hand babbled on average (x 44), but only the left arm
    is raised: the posture says left. The position rule says right."""
    params = DetectorParams(**{**vars(synthetic_params), "visibility_model": model})
    frame = draw(np.array([[44.0, 40.0], [np.nan, np.nan]]), BLOCKS)
    eyes = np.stack([frame, frame])
    by_posture = HandDetector(params, attribution="visibility")
    by_position = HandDetector(params, attribution="position")
    left_up = posture(0.9, -0.5)
    np.testing.assert_array_equal(by_posture.detect(eyes, left_up)[0], [[True, False]] * 2)
    np.testing.assert_array_equal(by_position.detect(eyes, left_up)[0], [[False, True]] * 2)
    right_up = posture(-0.5, 0.9)
    np.testing.assert_array_equal(by_posture.detect(eyes, right_up)[0], [[False, True]] * 2)
    # both arms up and two blobs: each hand, paired by the mean babbling positions
    both = draw(np.array([[20.0, 40.0], [44.0, 40.0]]), BLOCKS)
    detections, masks = by_posture.detect(np.stack([both, both]), posture(0.9, 0.9))
    assert detections.all()
    assert np.nonzero(masks[0, 0])[1].mean() < 32 < np.nonzero(masks[0, 1])[1].mean()
    # two blobs but only the left arm up: both are the left hand (one hand split in two)
    detections, masks = by_posture.detect(np.stack([both, both]), left_up)
    np.testing.assert_array_equal(detections, [[True, False]] * 2)
    assert masks[0, 0].sum() == pytest.approx(2 * masks[0, 0, :, :32].sum(), rel=0.1)
    # in a one-arm stage the moving arm's hand, as before
    np.testing.assert_array_equal(by_posture.detect(eyes, left_up, hands=[1])[0], [[0, 1]] * 2)


def test_a_detector_without_a_visibility_model_attributes_by_position_and_says_so(
    synthetic_params,
):
    with pytest.warns(UserWarning, match="no visibility model"):
        detector = HandDetector(synthetic_params, attribution="visibility")
    assert detector.attribution == "position"
    with pytest.raises(ValueError, match="valid: visibility, position"):
        HandDetector(synthetic_params, attribution="colour")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert HandDetector(None, attribution="visibility").attribution == "visibility"


def test_new_runs_attribute_by_visibility_and_saved_configs_by_position(
    synthetic_params, model, tmp_path
):
    assert HandRegardConfig().hand_attribution == "visibility"
    old = load_saved_config({"behavior": {"detector_file": "x.json"}}, HandRegard)
    assert old.behavior.hand_attribution == "position"  # how every published run was trained
    path = DetectorParams(**{**vars(synthetic_params), "visibility_model": model}).save(
        tmp_path / "hand_detector.json"
    )
    behavior = HandRegard(HandRegardConfig(detector_file=str(path)))
    assert behavior.detector.attribution == "visibility"
    behavior = HandRegard(HandRegardConfig(detector_file=str(path), hand_attribution="position"))
    assert behavior.detector.attribution == "position"
    assert DetectorParams.load(path).visibility_model == model  # the JSON round trip


def test_polynomial_features_are_the_products_of_each_monomials_factors():
    """The one-gather path gives the very numbers of multiplying each monomial's factors
    (the detector files' models were fitted that way), for any inputs and degree."""
    rng = np.random.default_rng(0)
    for k, degree in [(1, 1), (3, 2), (5, 3), (6, 3), (4, 4)]:
        x = rng.normal(size=(200, k)) * 3
        expected = np.stack([np.prod(x[:, list(m)], axis=1) for m in _monomials(k, degree)], axis=1)
        np.testing.assert_array_equal(polynomial_features(x, degree), expected)
    np.testing.assert_array_equal(polynomial_features(np.zeros((2, 3)), 0), np.ones((2, 1)))


def test_the_detectors_compiled_predictor_is_the_models_prediction(model, synthetic_params):
    params = DetectorParams(**{**vars(synthetic_params), "visibility_model": model})
    detector = HandDetector(params, attribution="visibility")
    for posture_ in (posture(0.9, -0.5), posture(-0.5, 0.9), posture(0.2, 0.3)):
        np.testing.assert_array_equal(
            detector.view_prior(posture_), predict_visibility(model, posture_)
        )
    zeros = [np.zeros_like(np.asarray(w)).tolist() for w in model["weights"]]
    params.visibility_model = {**model, "weights": zeros}  # a new model: compiled anew
    np.testing.assert_array_equal(detector.view_prior(posture(0.9, -0.5)), np.full((2, 2), 0.5))
    without = DetectorParams(**{**vars(synthetic_params), "visibility_model": {}})
    assert HandDetector(without).view_prior(posture(0.9, -0.5)) is None
    assert HandDetector(None).view_prior(posture(0.9, -0.5)) is None
