"""The behaviour on a rendering-free fake body: arm masking, facts, env steps, network, prepare."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
import torch
from devlearn_hand_regard import HandRegard, HandRegardConfig
from devlearn_hand_regard.behavior import DETECTOR_FILE
from devlearn_hand_regard.detector import DetectorParams
from fake_sitting import LEFT_ARM, RIGHT_ARM, FakeSittingInfant

from devlearn.api.errors import UsageError
from devlearn.testing import Play, facts_of, observations_of


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
    behavior.episode().hooks.on_episode_start(infant, None)  # reads the arm actuator groups
    action = np.linspace(-1, 1, 17)
    out = behavior.episode().hooks.process_action(action, stage_options(behavior, stage))
    assert np.all(out[zeroed] == 0)
    np.testing.assert_array_equal(out[kept], action[kept])
    np.testing.assert_array_equal(out[:3], action[:3])  # the head always moves
    assert action[zeroed].any() if len(zeroed) else True  # input untouched


def test_process_action_before_facts_fails_clearly():
    with pytest.raises(RuntimeError, match="arm actuator groups"):
        HandRegard().episode().hooks.process_action(np.zeros(17), {"active_arms": ["left"]})


def test_facts_detect_hands_and_motion(behavior):
    infant = FakeSittingInfant()
    infant.reset(None)
    facts = facts_of(behavior, infant)
    assert facts["hand_detections"].all() and facts["hand_count"] == 4
    assert facts["motion"] == 0.0  # first frame of the episode
    action = np.zeros(17)
    action[LEFT_ARM[0]] = 1.0  # left hand moves 2 px right
    infant.step(action)
    facts = facts_of(behavior, infant)
    per_pixel = facts["hand_flow"] / facts["hand_pixels"]  # (2 eyes, 2 hands) px per step
    assert np.all(per_pixel[:, 0] > 1.0) and np.all(per_pixel[:, 1] < 0.3)
    assert 0.0 < facts["motion"] < 0.08
    infant.step(action)  # moving on, the previous frame is still remembered
    assert facts_of(behavior, infant)["motion"] > 0.0
    infant.reset(None)  # a new episode: no motion from the old frame
    behavior.episode().hooks.on_episode_start(infant, None)
    assert facts_of(behavior, infant)["motion"] == 0.0


def test_env_steps_with_rewards_and_metrics(behavior):
    env = Play(behavior, infant_factory=FakeSittingInfant)
    [obs] = env.reset()
    assert set(obs) == {"proprioception", "hands_seen"}  # the default policy: no images
    assert obs["hands_seen"].shape == (16,) and obs["hands_seen"].dtype == np.float32
    env.set_stage(stage_options(behavior, "left_arm"))
    info = None
    for _ in range(env.episode_steps):
        [(obs, reward, done, _, info)] = env.step(np.zeros(17))
    assert done and info is not None
    # Left arm stage: both eyes see the left hand every step -> 0.5 - 0.05 per step.
    assert info["reward/hand_count"] == pytest.approx(0.5 * 20)
    assert info["reward/living_penalty"] == pytest.approx(-0.05 * 20)
    assert info["reward/bilateral_balance"] == 0.0
    # The switched-off right arm's hand is never credited in the left-arm stage (on the
    # infant it hangs out of view; the fake shows it anyway): a blob is the moving arm's hand.
    assert info["metrics/average"] == pytest.approx(0.5)
    assert info["metrics/left_eye_left_hand"] == pytest.approx(1.0)
    assert info["metrics/left_eye_right_hand"] == 0.0


def test_network_fuses_576_features(behavior):
    behavior.config.policy = "cnn"
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
    behavior.artifacts().prepare(tmp_path)
    assert behavior.config.detector_file == str((tmp_path / DETECTOR_FILE).resolve())
    assert behavior.detector.params == synthetic_params


def test_prepare_copies_a_given_detector_instead_of_babbling(
    tmp_path, synthetic_params, monkeypatch
):
    shared = synthetic_params.save(tmp_path / "shared.json")
    run = tmp_path / "run"
    run.mkdir()

    def no_babbling(*args, **kwargs):
        raise AssertionError("prepare must not babble when behavior.detector_file is given")

    monkeypatch.setattr("devlearn_hand_regard.babbling.babble", no_babbling)
    behavior = HandRegard()
    behavior.config.detector_file = str(shared)
    behavior.artifacts().prepare(run)
    assert behavior.config.detector_file == str((run / DETECTOR_FILE).resolve())
    assert DetectorParams.load(run / DETECTOR_FILE) == synthetic_params
    missing = HandRegard()
    missing.config.detector_file = str(tmp_path / "nope.json")
    with pytest.raises(UsageError, match="does not exist"):
        missing.artifacts().prepare(tmp_path / "other")


def test_behavior_pickles_without_runtime_state(behavior):
    infant = FakeSittingInfant()
    infant.reset(None)
    facts_of(behavior, infant)
    clone = pickle.loads(pickle.dumps(behavior))
    assert clone.hooks.flow.previous is None
    assert clone.config == behavior.config


def test_a_stored_detector_travels_to_workers(synthetic_params, tmp_path):
    """A policy file's detector has no file to be reloaded from in an env worker."""
    from devlearn_hand_regard import detector_store

    behavior = HandRegard(HandRegardConfig(detector_file=str(tmp_path / "moved_away.json")))
    stored = {"hand_detector": detector_store.as_artifact(synthetic_params)}
    behavior.artifacts().load_policy_artifacts(stored, tmp_path)
    clone = pickle.loads(pickle.dumps(behavior))
    assert clone.detector.params == synthetic_params


def test_cnn_policy_sees_the_eyes(behavior):
    """The actor sees the eyes and proprioception; the default (asymmetric) critic adds the
    detector's output, which the paper's critic (``critic=same``) does without."""
    behavior.config.policy = "cnn"
    [obs] = Play(behavior, infant_factory=FakeSittingInfant).reset()
    assert set(obs) == {"left_eye", "right_eye", "proprioception", "hands_seen"}
    assert behavior.network().obs_groups(list(obs))["actor"] == [
        "left_eye",
        "right_eye",
        "proprioception",
    ]
    assert obs["left_eye"].shape == (64, 64, 3) and obs["left_eye"].dtype == np.uint8
    behavior.config.critic = "same"
    [obs] = Play(behavior, infant_factory=FakeSittingInfant).reset()
    assert set(obs) == {"left_eye", "right_eye", "proprioception"}


def test_proprio_policy_sees_the_detector_output(behavior):
    """Proprioception plus per (eye, hand): detected, centre x and y in [-1, 1], area share;
    the reward still comes from the images through the detector."""
    from devlearn_hand_regard.behavior import hand_features

    infant = FakeSittingInfant()  # left hand disc at x 20, right at x 44, both at y 40
    infant.reset(None)
    behavior.episode().hooks.on_episode_start(infant, None)
    facts = facts_of(behavior, infant)
    obs = observations_of(behavior, infant, facts)
    features = obs["hands_seen"].reshape(2, 2, 4)
    assert np.all(features[..., 0] == 1.0)
    np.testing.assert_allclose(features[:, 0, 1], 2 * 20.5 / 64 - 1, atol=0.05)
    np.testing.assert_allclose(features[:, 1, 1], 2 * 44.5 / 64 - 1, atol=0.05)
    np.testing.assert_allclose(features[..., 2], 2 * 40.5 / 64 - 1, atol=0.05)
    assert np.all((features[..., 3] > 0.01) & (features[..., 3] < 0.05))  # ~81 px of 4096
    np.testing.assert_array_equal(obs["proprioception"], infant.proprioception())
    none = hand_features(np.zeros((2, 2), bool), np.zeros((2, 2, 64, 64), bool))
    assert none.shape == (16,) and not none.any()
    spec = behavior.network()
    assert set(spec.encoders) == {"proprioception", "hands_seen"} and spec.share
    net = spec.encoders["hands_seen"].build((16,))
    assert net(torch.zeros(3, 16)).shape == (3, 32)


def test_scene_start_and_policy_defaults_and_legacy():
    from devlearn.testing import load_saved_config

    behavior = HandRegard()
    assert behavior.scene == "sitting_babybench" and HandRegard.scene == "sitting_babybench"
    assert behavior.episode().infant_options == {"appearance": "mittens", "start": "babybench"}
    assert behavior.evaluation().stage == {"active_arms": ["left", "right"], "random_pose": False}
    assert behavior.config.policy == "proprio" and not behavior.episode().facts_every_physics_step
    # A config saved before issue #29 lacks these keys: the old scene, start, eval and network.
    old = load_saved_config({"behavior": {"detector_file": "x.json"}}, HandRegard)
    legacy = HandRegard(old.behavior)
    assert legacy.scene == "sitting" and legacy.config.policy == "cnn"
    assert legacy.episode().infant_options["start"] == "rest"
    assert legacy.evaluation().stage["random_pose"] is True
    with pytest.raises(Exception, match="valid: sitting_babybench, sitting"):
        HandRegard(HandRegardConfig(scene="crib")).episode()


def test_demonstration_by_default_and_the_paper_preset():
    from devlearn.testing import run_config

    demo = run_config(HandRegard)
    assert demo.total_steps == 200_000 and demo.behavior.policy == "proprio"
    assert (demo.behavior.left_arm_steps, demo.behavior.right_arm_steps) == (20_000, 20_000)
    assert demo.behavior.both_arms_steps == 160_000
    paper = run_config(HandRegard, preset="paper")
    assert paper.total_steps == 1_850_000 and paper.behavior.policy == "cnn"
    assert (paper.behavior.left_arm_steps, paper.behavior.both_arms_steps) == (175_000, 1_500_000)


def test_stage_lengths_scale_with_the_run_unless_set():
    """A run of N steps goes through all three stages (10% + 10% + the rest, as the 614,400-step
    experiments did); --set and the paper preset keep their own lengths."""
    from devlearn.testing import PluginRegistry, run_config

    registry = PluginRegistry()

    def stages(overrides=(), preset="", **top):
        b = run_config(HandRegard, overrides, preset, registry=registry, **top).behavior
        return b.left_arm_steps, b.right_arm_steps, b.both_arms_steps

    assert stages() == (20_000, 20_000, 160_000)  # the demonstration
    assert stages(total_steps=614_400) == (61_440, 61_440, 491_520)
    assert stages(preset="paper") == (175_000, 175_000, 1_500_000)
    set_left = ["behavior.left_arm_steps=5000"]
    assert stages(set_left, total_steps=614_400) == (5_000, 61_440, 491_520)


def test_an_unusable_detector_file_is_one_line(tmp_path):
    import pytest

    from devlearn import UsageError

    not_a_detector = tmp_path / "other.json"
    not_a_detector.write_text('{"a": 1}')
    broken = tmp_path / "broken.json"
    broken.write_text("[1")
    for path, reason in (
        (tmp_path / "missing.json", "No such file or directory"),
        (not_a_detector, "hand detector format None"),
        (broken, "Expecting"),
    ):
        behavior = HandRegard(HandRegardConfig(detector_file=str(path)))
        with pytest.raises(UsageError, match=f"behavior.detector_file {path}: .*{reason}"):
            behavior.detector  # noqa: B018 (loads the file)


def test_asymmetric_critic_trains_without_eye_cnns(tmp_path, detector_file):
    """``critic=proprio`` under the paper's CNN policy: the actor keeps both eye CNNs and the
    proprioception MLP; the critic sees proprioception and the detector's output only, so
    the update runs two eye CNNs, not four. A tiny run trains, and its policy file acts on
    the actor's observations alone."""
    from devlearn.testing import PluginRegistry, policy_network, run_config, train

    overrides = [
        "behavior.policy=cnn",
        "behavior.critic=proprio",
        f"behavior.detector_file={detector_file}",
        "behavior.left_arm_steps=16",
        "behavior.right_arm_steps=16",
        "ppo.num_steps_per_env=8",
        "ppo.num_mini_batches=2",
        "env.action_repeat=1",
    ]
    cfg = run_config(
        HandRegard, overrides, total_steps=48, num_envs=2, workers=0, seed=1, out_dir=tmp_path
    )
    assert cfg.network.layout == "separate"
    behavior = HandRegard(cfg.behavior)
    [obs] = Play(behavior, infant_factory=FakeSittingInfant).reset()
    assert set(obs) == {"left_eye", "right_eye", "proprioception", "hands_seen"}
    assert behavior.network().obs_groups(list(obs)) == {
        "actor": ["left_eye", "right_eye", "proprioception"],
        "critic": ["proprioception", "hands_seen"],
    }
    result = train(cfg, PluginRegistry(), infant_factory=FakeSittingInfant, progress=False)
    state = torch.load(result.run_dir / "checkpoint_latest.pt", weights_only=False)
    actor = {k.split(".")[1] for k in state["actor_state_dict"] if k.startswith("encoders.")}
    critic = {k.split(".")[1] for k in state["critic_state_dict"] if k.startswith("encoders.")}
    assert actor == {"left_eye", "right_eye", "proprioception"}
    assert critic == {"proprioception", "hands_seen"}
    policy = policy_network(cfg, behavior, obs, 17, state["actor_state_dict"])
    batch = {k: torch.as_tensor(v)[None] for k, v in obs.items() if k != "hands_seen"}
    assert policy(batch).shape == (1, 17)


def test_critic_choice_is_checked(behavior):
    behavior.config.critic = "eyes"
    with pytest.raises(UsageError, match="critic.*same.*proprio"):
        behavior.network()


def test_an_asymmetric_critic_with_a_shared_body_is_refused_up_front():
    from devlearn.testing import run_config

    asymmetric = ["behavior.policy=cnn", "behavior.critic=proprio"]
    with pytest.raises(UsageError, match="network.layout=shared needs the actor and the critic"):
        run_config(HandRegard, [*asymmetric, "network.layout=shared"])
    assert run_config(
        HandRegard, ["behavior.policy=cnn", "behavior.critic=same", "network.layout=shared"]
    )
    with pytest.raises(UsageError, match="network.layout=shared needs"):  # the default critic
        run_config(HandRegard, ["behavior.policy=cnn", "network.layout=shared"])


def test_the_cnn_policy_trains_with_the_asymmetric_critic_unless_told_or_saved_otherwise():
    """Issue #40: ``policy=cnn`` gets the critic without eye CNNs by default; the paper preset
    keeps the paper's critic, and a config saved before the key existed loads as trained."""
    from devlearn.testing import load_saved_config, run_config, saved_config

    fresh = run_config(HandRegard, ["behavior.policy=cnn"])
    assert fresh.behavior.critic == "proprio"
    groups = (
        HandRegard(fresh.behavior)
        .network()
        .obs_groups(["left_eye", "right_eye", "proprioception", "hands_seen"])
    )
    assert groups["critic"] == ["proprioception", "hands_seen"]
    assert run_config(HandRegard, preset="paper").behavior.critic == "same"
    saved = saved_config(fresh)
    del saved["behavior"]["critic"]  # as issue #29's CNN runs saved theirs
    assert load_saved_config(saved, HandRegard).behavior.critic == "same"


def test_a_detector_file_with_values_no_calibration_writes_is_one_line(tmp_path, detector_file):
    # issue #55, faults 7 and 8: NaN areas, empty or NaN colour boxes and JSON nested 100k deep
    # were taken (detecting nothing, or everything) or a RecursionError traceback
    import json
    import re
    from pathlib import Path

    good = json.loads(Path(detector_file).read_text())
    deep = tmp_path / "deep.json"
    deep.write_text('{"a":' * 100_000 + "1" + "}" * 100_000)
    cases = [
        ({"min_area": float("nan")}, "min_area, max_area and expected_area must be finite"),
        ({"expected_area": float("inf")}, "min_area, max_area and expected_area must be finite"),
        ({"min_area": 50.0, "max_area": 10.0}, "0 <= min_area <= max_area"),
        ({"hsv_ranges": []}, "hsv_ranges must be a non-empty list of colour boxes"),
        ({"hsv_ranges": [[float("nan")] * 6]}, "hsv_ranges holds [nan, nan"),
        ({"hsv_ranges": [[0, 0, 0, 200, 255, 255]]}, "H up to 179"),
        ({"side_hsv_ranges": [[]]}, "side_hsv_ranges must be [] or [left boxes, right boxes]"),
        ({"hand_means": [[[float("nan"), 1.0]]]}, "hand_means (eyes x 2 hands x [x, y]) must be"),
        ({"kernel": 0}, "kernel must be a whole number of pixels from 1"),
        ({"hsv": 1}, "not a hand detector (unknown field(s) hsv)"),
    ]
    for i, (change, reason) in enumerate(cases):
        path = tmp_path / f"bad{i}.json"
        path.write_text(json.dumps({**good, **change}))
        expected = f"hand_regard: behavior.detector_file {path}: .*" + re.escape(reason)
        with pytest.raises(UsageError, match=expected):
            HandRegard(HandRegardConfig(detector_file=str(path))).detector  # noqa: B018
        run = tmp_path / f"run{i}"
        with pytest.raises(UsageError, match=expected):
            HandRegard(HandRegardConfig(detector_file=str(path))).artifacts().prepare(run)
        assert not (run / DETECTOR_FILE).exists()
    behavior = HandRegard(HandRegardConfig(detector_file=str(deep)))
    with pytest.raises(UsageError, match="its JSON is nested too deeply"):
        behavior.detector  # noqa: B018
    stored = {"format_version": 2, **{**good, "min_area": float("nan")}}
    with pytest.raises(UsageError, match="the checkpoint's hand detector: min_area"):
        HandRegard().artifacts().load_policy_artifacts({"hand_detector": stored}, tmp_path)
