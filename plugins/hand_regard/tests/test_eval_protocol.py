"""Hand-regard evaluation episodes: BabyBench's seeded starts (the default) and random starts
(the generalisation row, and runs before issue #29) that differ; self-contained runs."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from devlearn_hand_regard import HandRegard, HandRegardConfig

from devlearn import build_infant
from devlearn.api.errors import UsageError
from devlearn.testing import Play

RESULTS = Path(__file__).resolve().parents[3] / "results" / "hand_regard"


@pytest.fixture(scope="module")
def sitting():
    infant = build_infant("sitting", senses=("proprioception", "eyes"))
    yield infant
    infant.close()


def starts(seed, episodes, sitting, detector_file, eval_start="random"):
    """Joint angles and toy positions at the start of each evaluation episode."""
    behavior = HandRegard(HandRegardConfig(eval_start=eval_start))
    behavior.config.detector_file = str(detector_file)
    env = Play(
        behavior, seed=seed, infant_factory=lambda scene, senses, **options: sitting, training=False
    )
    env.set_stage(behavior.evaluation().stage)
    toys = [g for g in range(sitting.model.ngeom) if sitting.model.geom(g).name.startswith("toy")]
    out = []
    for _ in range(episodes):
        env.reset()
        out.append((sitting.data.qpos.copy(), sitting.model.geom_pos[toys].copy()))
    return out


def test_evaluation_episodes_differ_and_repeat_with_the_seed(sitting, detector_file):
    first = starts(3, 3, sitting, detector_file)
    again = starts(3, 3, sitting, detector_file)
    other = starts(4, 1, sitting, detector_file)
    for (q, toys), (q2, toys2) in zip(first, again):
        np.testing.assert_array_equal(q, q2)  # same seed, same episodes
        np.testing.assert_array_equal(toys, toys2)
    for a, b in ((0, 1), (1, 2), (0, 2)):
        assert np.abs(first[a][0] - first[b][0]).max() > 0.05  # postures differ
        assert np.abs(first[a][1] - first[b][1]).max() > 0.01  # toys moved
    assert np.abs(first[0][0] - other[0][0]).max() > 0.05
    head, arms = sitting.actuator_groups["head"], sitting.actuator_groups["left_arm"]
    assert np.ptp([q[head] for q, _ in first], axis=0).min() > 0  # every head joint varies
    assert np.ptp([q[arms] for q, _ in first], axis=0).min() > 0
    random = HandRegard(HandRegardConfig(eval_start="random")).evaluation().stage
    assert random == {"active_arms": ["left", "right"], "random_pose": True}


@pytest.fixture(scope="module")
def babybench():
    infant = build_infant("sitting_babybench", senses=("proprioception", "eyes"), start="babybench")
    yield infant
    infant.close()


def test_babybench_evaluation_episodes_differ_by_their_kicks(babybench, detector_file):
    """The default protocol: every episode from the settled state plus 10 seeded random-action
    steps, so the deterministic policy's episodes differ a little and repeat with the seed."""
    first = starts(3, 3, babybench, detector_file, eval_start="babybench")
    again = starts(3, 3, babybench, detector_file, eval_start="babybench")
    for (q, toys), (q2, toys2) in zip(first, again):
        np.testing.assert_array_equal(q, q2)
        np.testing.assert_array_equal(toys, toys2)  # the toys stay in their places
    for a, b in ((0, 1), (1, 2)):
        assert 1e-4 < np.abs(first[a][0] - first[b][0]).max() < 0.3  # kicked, not random


def test_training_start_keeps_the_toys_in_place(sitting):
    toys = [g for g in range(sitting.model.ngeom) if sitting.model.geom(g).name.startswith("toy")]
    sitting.reset(np.random.default_rng(0), random_pose=True)
    moved = sitting.model.geom_pos[toys].copy()
    sitting.reset(np.random.default_rng(0))
    np.testing.assert_allclose(
        sitting.model.geom_pos[toys][:, :2],
        [[0.24, 0.05], [0.3, -0.07], [0.37, 0.02], [0.21, -0.02]],
    )
    assert np.abs(moved - sitting.model.geom_pos[toys]).max() > 0.01


def test_detector_is_found_beside_a_relocated_checkpoint(tmp_path, detector_file):
    original = tmp_path / "original"
    original.mkdir()
    shutil.copy(detector_file, original / "hand_detector.json")
    behavior = HandRegard()
    behavior.config.detector_file = str(original / "hand_detector.json")  # absolute, as saved
    moved = tmp_path / "elsewhere" / "run"
    shutil.copytree(original, moved)
    shutil.rmtree(original)
    behavior.artifacts().load_policy_artifacts({}, moved)
    assert behavior.config.detector_file == str(moved / "hand_detector.json")
    assert behavior.detector.params is not None
    (moved / "hand_detector.json").unlink()
    with pytest.raises(UsageError, match="hand_detector.json"):
        HandRegard(behavior.config).artifacts().load_policy_artifacts({}, moved)


def test_policy_artifacts_carry_the_detector(detector_file):
    behavior = HandRegard()
    behavior.config.detector_file = str(detector_file)
    artifacts = json.loads(json.dumps(behavior.artifacts().policy_artifacts()))  # plain data only
    restored = HandRegard()
    restored.config.detector_file = "/nowhere/hand_detector.json"
    restored.artifacts().load_policy_artifacts(artifacts, detector_file.parent)
    assert restored.detector.params == behavior.detector.params


def old_run_policy(detector_file: Path) -> dict:
    """A policy file's state as a run before issue #29 saved it: results/hand_regard/run's
    config (old scene, random starts; its policy file is in git history since 2d704d9) with
    an actor of that config and the detector among its artifacts. The weights are fresh: these
    tests check the evaluation protocol, not what the policy does."""
    from devlearn.testing import load_saved_config, policy_file, policy_network

    saved = json.loads((RESULTS / "run" / "config.json").read_text())
    saved["behavior"]["detector_file"] = str(detector_file)
    cfg = load_saved_config(saved, HandRegard)
    behavior = HandRegard(cfg.behavior)
    env = Play(behavior, training=False)
    try:
        env.set_stage(behavior.evaluation().stage)
        [obs] = env.reset()
        actor = policy_network(cfg, behavior, obs, env.action_dim)
    finally:
        env.close()
    return policy_file(saved, behavior, actor.state_dict())


def test_relocated_run_folder_evaluates(tmp_path, detector_file):
    """A run whose config names its detector by an absolute path, moved after training."""
    from devlearn.testing import PluginRegistry, evaluate_policy, save_checkpoint

    state = old_run_policy(detector_file)
    original = tmp_path / "original"
    original.mkdir()
    detector = state.pop("artifacts")["hand_detector"]
    (original / "hand_detector.json").write_text(json.dumps(detector))
    state["config"]["behavior"]["detector_file"] = str(original / "hand_detector.json")
    save_checkpoint(state, original / "checkpoint_latest.pt")  # as a training run leaves it
    moved = tmp_path / "moved" / "run"
    shutil.copytree(original, moved)
    shutil.rmtree(original)

    def short(scene, **kwargs):
        infant = build_infant(scene, **kwargs)
        infant.episode_steps = 30
        return infant

    summary = evaluate_policy(
        "hand_regard",
        moved,
        1,
        PluginRegistry(),
        infant_factory=short,
        out_dir=tmp_path / "eval",
        progress=False,
    )
    assert summary["steps"] == 30 and summary["headline_criterion"] == "detector"
    assert set(summary["criteria"]) == {"detector", "pixels", "babybench", "cone", "any_pixel"}
    assert summary["protocol"]["criteria"]["cone"]["max_angle_deg"] == 15.0
    # Its saved config predates issue #29: the old scene, evaluated from random starts.
    assert summary["start"] == "random" and summary["protocol"]["stage"]["random_pose"]
    assert summary["config"]["behavior"].get("scene") is None


def test_an_old_policy_file_evaluates_from_babybench_start(tmp_path, detector_file):
    """`devlearn eval hand_regard --start babybench` on a policy file of the old scene."""
    from devlearn.testing import PluginRegistry, evaluate_policy, save_checkpoint

    policy = tmp_path / "policy.pt"
    save_checkpoint(old_run_policy(detector_file), policy)
    scenes = []

    def short(scene, **kwargs):
        scenes.append((scene, kwargs.get("start")))
        infant = build_infant(scene, **kwargs)
        infant.episode_steps = 20
        return infant

    summary = evaluate_policy(
        "hand_regard",
        policy,
        1,
        PluginRegistry(),
        infant_factory=short,
        out_dir=tmp_path / "eval",
        progress=False,
        start="babybench",
    )
    assert scenes == [("sitting", "rest")]  # the scene it trained in
    assert summary["start"] == "babybench" and summary["protocol"]["start_option"] == "babybench"
    saved = json.loads((tmp_path / "eval" / "eval.json").read_text())
    assert saved["start"] == "babybench" and saved["headline_criterion"] == "detector"


def test_eval_start_differs_from_the_training_start(tmp_path):
    """Trained from rest, evaluated (``--start stage``) from its ``eval_start``, babybench."""
    from devlearn.testing import PluginRegistry, evaluate_policy

    built = []

    def short(scene, **kwargs):
        built.append(kwargs.get("start"))
        infant = build_infant(scene, **kwargs)
        infant.episode_steps = 5
        return infant

    summary = evaluate_policy(
        "hand_regard",
        None,
        1,
        PluginRegistry(),
        infant_factory=short,
        progress=False,
        policy="zero",
        overrides=["behavior.start=rest"],
    )
    assert built == ["rest"] and summary["start"] == "babybench"
    assert summary["protocol"]["start_option"] == "stage"
