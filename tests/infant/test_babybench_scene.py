"""BabyBench's hand-regard scene (``sitting_babybench``) and the episode starts (issue #29)."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from devlearn.infant import build_infant
from devlearn.infant.scenes import BABYBENCH_HEAD_PITCH
from devlearn.infant.starts import KICK_STEPS, STARTS


@pytest.fixture(scope="module")
def babybench():
    with build_infant("sitting_babybench", senses=("proprioception", "eyes")) as infant:
        yield infant


def _head(infant) -> np.ndarray:
    """(swivel, tilt, side tilt) angles, rad."""
    return infant.data.qpos[infant._qpos_index[infant.actuator_groups["head"]]]


def _angles(axes: np.ndarray, origins: np.ndarray, hands: np.ndarray) -> np.ndarray:
    """(2 eyes, 2 hands) degrees between each eye's ``axes`` row and the vector from its
    ``origins`` row to each hand's point (``hands``: (2, 3), left then right)."""
    to_hand = hands[None] - origins[:, None]
    cos = np.einsum("ek,ehk->eh", axes, to_hand) / np.linalg.norm(to_hand, axis=2)
    return np.degrees(np.arccos(np.clip(cos, -1, 1)))


def _hands(infant) -> list[int]:
    return [infant.model.body(f"{hand}_hand").id for hand in ("left", "right")]


def _axis_angles(infant) -> np.ndarray:
    """(2 eyes, 2 hands) degrees between each eye camera's optical axis (its frame's -z) and
    the direction to each hand's centre of mass."""
    data = infant.data
    camera = mujoco.mjtObj.mjOBJ_CAMERA
    cams = [mujoco.mj_name2id(infant.model, camera, f"{eye}_eye") for eye in ("left", "right")]
    axes = -data.cam_xmat[cams].reshape(2, 3, 3)[:, :, 2]
    return _angles(axes, data.cam_xpos[cams], data.xipos[_hands(infant)])


def _babybench_angles(infant) -> np.ndarray:
    """(2 eyes, 2 hands) degrees between each eye *body's* -z axis and the eye-to-hand vector
    (body origins): BabyBench's hand-regard counter, 90 degrees below the optical axis."""
    data = infant.data
    eyes = [infant.model.body(f"{eye}_eye").id for eye in ("left", "right")]
    axes = -data.xmat[eyes].reshape(2, 3, 3)[:, :, 2]
    return _angles(axes, data.xpos[eyes], data.xpos[_hands(infant)])


def test_seventeen_motors_head_pitch_and_side_tilt_held(babybench):
    assert babybench.action_dim == 17  # the held joints keep their motors, as in BabyBench
    assert babybench.model.neq == 2
    rng = np.random.default_rng(0)
    babybench.reset(rng, start="babybench")
    swivel = []
    for _ in range(300):  # full-strength random head torques
        action = np.zeros(17)
        action[babybench.actuator_groups["head"]] = rng.uniform(-1, 1, 3)
        babybench.step(action)
        head = _head(babybench)
        assert abs(head[1] - BABYBENCH_HEAD_PITCH) < 0.03 and abs(head[2]) < 0.03
        swivel.append(head[0])
    assert np.ptp(swivel) > 0.05  # the swivel is free


def test_start_hands_far_off_both_optical_axes(babybench):
    for start in ("rest", "babybench"):
        for seed in range(3):
            babybench.reset(np.random.default_rng(seed), start=start)
            angles = _axis_angles(babybench)
            assert angles.min() >= 80.0 and angles.max() < 90.0, start  # BabyBench: 80-86
            assert not np.isin(babybench.eyes_segmentation(), (1, 2)).any()


@pytest.mark.slow
@pytest.mark.parametrize("policy", ["zero", "random"])
def test_baselines_see_no_hand_over_an_episode(babybench, policy):
    """From the training start, neither doing nothing nor i.i.d. uniform actions at 200 Hz
    bring a single hand pixel into either eye over a 1000-step episode (BabyBench: both 0)."""
    rng = np.random.default_rng(5)
    babybench.reset(rng, start="babybench")
    counted = 0
    for _ in range(babybench.episode_steps):
        babybench.step(np.zeros(17) if policy == "zero" else rng.uniform(-1, 1, 17))
        assert not np.isin(babybench.eyes_segmentation(), (1, 2)).any()
        counted += int((_babybench_angles(babybench) < 15.0).sum())
    if policy == "zero":  # BabyBench's own counter credits doing nothing with 0, as there
        assert counted == 0


def test_rest_is_the_settled_state_and_babybench_kicks_it(babybench):
    babybench.reset(np.random.default_rng(0), start="rest")
    rest = babybench.data.qpos.copy()
    # settled: 100 zero-action steps (0.5 s) from the scene's pose, not the pose itself
    assert np.abs(rest[babybench._qpos_index] - babybench._rest).max() > 0.01
    babybench.reset(np.random.default_rng(1), start="rest")
    np.testing.assert_array_equal(babybench.data.qpos, rest)  # rest: the same every episode
    kicked = []
    for seed in (0, 1, 0):
        babybench.reset(np.random.default_rng(seed), start="babybench")
        kicked.append(babybench.data.qpos.copy())
        assert np.all(babybench.data.ctrl == 0.0) and babybench.steps == 0
    np.testing.assert_array_equal(kicked[0], kicked[2])  # seeded
    assert np.abs(kicked[0] - kicked[1]).max() > 1e-4  # the kicks differ by seed
    assert np.abs(kicked[0] - rest).max() > 1e-4
    assert KICK_STEPS == 10 and STARTS == ("babybench", "rest", "random")


def test_random_start_keeps_the_held_joints(babybench):
    babybench.reset(np.random.default_rng(3), start="random")
    head = _head(babybench)
    assert head[1] == pytest.approx(BABYBENCH_HEAD_PITCH) and head[2] == pytest.approx(0.0)


def test_infant_start_option(babybench):
    infant = build_infant("crib", senses=("proprioception",), start="babybench")
    try:
        assert infant.start == "babybench" and infant.describe()["start"] == "babybench"
        infant.reset(np.random.default_rng(0))
        assert np.abs(infant.data.qvel).max() > 0  # kicked: moving
        infant.reset(np.random.default_rng(0), random_pose=True)  # random_pose still wins
    finally:
        infant.close()
    with pytest.raises(ValueError, match="valid starts"):
        build_infant("crib", senses=(), start="sideways")


def test_old_sitting_scene_unchanged():
    """Runs before issue #29 trained in ``sitting``: head free, rest pose unsettled."""
    infant = build_infant("sitting", senses=("proprioception",))
    try:
        assert infant.model.neq == 0 and infant.action_dim == 17
        infant.reset(np.random.default_rng(0))
        assert _head(infant)[1] == pytest.approx(0.5)
        assert np.all(infant.data.qvel == 0)
    finally:
        infant.close()
