"""The behaviour on a rendering-free fake body: arm masking, facts, env steps, network, prepare."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
import torch
from devlearn_hand_regard import HandRegard, HandRegardConfig
from devlearn_hand_regard.behavior import DETECTOR_FILE
from fake_sitting import LEFT_ARM, RIGHT_ARM, FakeSittingInfant

from devlearn.env import BehaviorEnv


@pytest.fixture()
def behavior(detector_file):
    return HandRegard(HandRegardConfig(detector_file=str(detector_file)))


def stage_options(behavior, name):
    return next(s.options for s in behavior.curriculum().stages if s.name == name)


def test_curriculum_stages_and_lengths():
    stages = HandRegard(HandRegardConfig(left_arm_steps=10, right_arm_steps=20)).curriculum()
    assert [(s.name, s.steps) for s in stages.stages] == [
        ("left_arm", 10),
        ("right_arm", 20),
        ("both_arms", None),
    ]
    assert [(s.name, s.steps) for s in HandRegard().curriculum().stages[:2]] == [
        ("left_arm", 175_000),
        ("right_arm", 175_000),
    ]


@pytest.mark.parametrize(
    ("stage", "zeroed", "kept"),
    [
        ("left_arm", RIGHT_ARM, LEFT_ARM),
        ("right_arm", LEFT_ARM, RIGHT_ARM),
        ("both_arms", np.array([], int), np.concatenate([LEFT_ARM, RIGHT_ARM])),
    ],
)
def test_process_action_masks_the_inactive_arm(behavior, stage, zeroed, kept):
    infant = FakeSittingInfant()
    infant.reset(None)
    behavior.on_episode_start(infant, None)  # reads the arm actuator groups
    action = np.linspace(-1, 1, 17)
    out = behavior.process_action(action, stage_options(behavior, stage))
    assert np.all(out[zeroed] == 0)
    np.testing.assert_array_equal(out[kept], action[kept])
    np.testing.assert_array_equal(out[:3], action[:3])  # the head always moves
    assert action[zeroed].any() if len(zeroed) else True  # input untouched


def test_process_action_before_facts_fails_clearly():
    with pytest.raises(RuntimeError, match="arm actuator groups"):
        HandRegard().process_action(np.zeros(17), {"active_arms": ["left"]})


def test_facts_detect_hands_and_motion(behavior):
    infant = FakeSittingInfant()
    infant.reset(None)
    facts = behavior.facts(infant)
    assert facts["hand_detections"].all() and facts["hand_count"] == 4
    assert facts["motion"] == 0.0  # first frame of the episode
    action = np.zeros(17)
    action[LEFT_ARM[0]] = 1.0  # left hand moves 2 px right
    infant.step(action)
    facts = behavior.facts(infant)
    per_pixel = facts["hand_flow"] / facts["hand_pixels"]  # (2 eyes, 2 hands) px per step
    assert np.all(per_pixel[:, 0] > 1.0) and np.all(per_pixel[:, 1] < 0.3)
    assert 0.0 < facts["motion"] < 0.08
    infant.step(action)  # moving on, the previous frame is still remembered
    assert behavior.facts(infant)["motion"] > 0.0
    infant.reset(None)  # a new episode: no motion from the old frame
    behavior.on_episode_start(infant, None)
    assert behavior.facts(infant)["motion"] == 0.0


def test_env_steps_with_rewards_and_metrics(behavior):
    env = BehaviorEnv(behavior, seed=0, infant_factory=FakeSittingInfant)
    obs = env.reset()
    assert obs["left_eye"].shape == (64, 64, 3) and obs["left_eye"].dtype == np.uint8
    env.set_stage(stage_options(behavior, "left_arm"))
    info = None
    for _ in range(env.episode_steps):
        obs, reward, done, _, info = env.step(np.zeros(17))
    assert done and info is not None
    # Left arm stage: both eyes see the left hand every step -> 0.5 - 0.05 per step.
    assert info["reward/hand_count"] == pytest.approx(0.5 * 20)
    assert info["reward/living_penalty"] == pytest.approx(-0.05 * 20)
    assert info["reward/bilateral_balance"] == 0.0
    assert info["metrics/average"] == pytest.approx(1.0)
    assert info["metrics/left_eye_right_hand"] == pytest.approx(1.0)


def test_network_fuses_576_features(behavior):
    spec = behavior.network()
    shapes = {"left_eye": (64, 64, 3), "right_eye": (64, 64, 3), "proprioception": (21,)}
    dims = {k: spec.encoders[k].out_dim(s) for k, s in shapes.items()}
    assert sum(dims.values()) == 576 and spec.fusion_dims == (256,) and spec.trunk_dims == ()
    assert spec.normalize == ("proprioception",)  # running mean/var before the MLP
    assert spec.share  # one fused representation feeds both heads (paper, Model II)
    eye = spec.encoders["left_eye"].build((64, 64, 3))
    images = torch.rand(2, 64, 64, 3)  # the SensorEncoder contract: [0, 1] floats
    assert eye(images).shape == (2, 256)
    proprio = spec.encoders["proprioception"].build((21,))
    assert proprio(torch.zeros(2, 21)).shape == (2, 64)


def test_prepare_reuses_the_saved_detector(tmp_path, synthetic_params, monkeypatch):
    synthetic_params.save(tmp_path / DETECTOR_FILE)

    def no_babbling(*args, **kwargs):
        raise AssertionError("prepare must not babble when the run has a detector")

    monkeypatch.setattr("devlearn_hand_regard.babbling.babble", no_babbling)
    behavior = HandRegard()
    behavior.prepare(tmp_path)
    assert behavior.config.detector_file == str((tmp_path / DETECTOR_FILE).resolve())
    assert behavior.detector.params == synthetic_params


def test_behavior_pickles_without_runtime_state(behavior):
    infant = FakeSittingInfant()
    infant.reset(None)
    behavior.facts(infant)
    clone = pickle.loads(pickle.dumps(behavior))
    assert clone._detector is None and clone._flow.previous is None
    assert clone.config == behavior.config
