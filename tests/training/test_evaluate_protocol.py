"""``devlearn eval``'s protocol: baselines on the checkpoint's code path, the protocol in the
JSON, run folders as --checkpoint, output folders checked first, summaries never lost."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "env"))

import devlearn.plugins  # noqa: E402
from devlearn.api.errors import UsageError  # noqa: E402
from devlearn.cli import main  # noqa: E402
from devlearn.evaluation.evaluate import EvalRequest, Evaluation  # noqa: E402
from devlearn.testing import registry_for  # noqa: E402
from devlearn.testing.fake_infant import FakeInfant, TinyBehavior  # noqa: E402


class RecordingInfant(FakeInfant):
    """A fake infant that keeps every action it was given (and every age it was built at)."""

    log: list = []
    ages: list = []

    def step(self, action):
        RecordingInfant.log.append(np.array(action))
        super().step(action)


def recording(scene, senses=("proprioception",), **kwargs):
    RecordingInfant.ages.append(kwargs.get("age_months"))
    return RecordingInfant(scene, senses, episode_steps=10, age_months=kwargs.get("age_months"))


@pytest.fixture
def registry(monkeypatch):
    registry = registry_for(TinyBehavior)
    monkeypatch.setattr(devlearn.plugins, "PluginRegistry", lambda *a, **k: registry)
    monkeypatch.setattr("devlearn.env.behavior_env.build_default_infant", recording)
    RecordingInfant.log = []
    return registry


@pytest.fixture
def run_dir(registry, tmp_path):
    out = tmp_path / "run"
    assert (
        main(["run", "tiny", "--steps", "16", "--envs", "2", "--seed", "3", "--out", str(out)]) == 0
    )
    RecordingInfant.log = []
    return out


def eval_run(run_dir: Path, *options: str) -> int:
    """``devlearn eval tiny --checkpoint RUN_DIR --episodes 1 OPTIONS``: its exit code."""
    return main(["eval", "tiny", "--checkpoint", str(run_dir), "--episodes", "1", *options])


def actions_of(registry, checkpoint, policy, seed=0):
    RecordingInfant.log = []
    summary = Evaluation(
        EvalRequest("tiny", checkpoint, episodes=2, seed=seed, policy=policy),
        registry,
        progress=False,
    ).run()
    return np.array(RecordingInfant.log), summary


def test_baselines_run_through_the_checkpoint_path(registry, run_dir):
    checkpoint = run_dir / "checkpoint_latest.pt"
    trained, s_ckpt = actions_of(registry, checkpoint, "checkpoint")
    zero, s_zero = actions_of(registry, None, "zero")
    rand, s_rand = actions_of(registry, None, "random")
    again, _ = actions_of(registry, None, "random")
    assert trained.shape == zero.shape == rand.shape == (20, 3)  # same episodes, same steps
    assert np.abs(trained).max() > 0 and not zero.any()
    assert np.abs(rand).max() <= 1 and rand.std() > 0.3  # uniform in [-1, 1]
    np.testing.assert_array_equal(rand, again)  # seeded by the evaluation seed
    assert not np.array_equal(rand, actions_of(registry, None, "random", seed=1)[0])
    # the same record, but for the network's own figures (its mean action at the bounds)
    assert "policy_figures" in s_ckpt and "policy_figures" not in s_zero
    assert set(s_ckpt) - {"policy_figures"} == set(s_zero) == set(s_rand)
    assert (s_ckpt["policy"], s_zero["policy"], s_rand["policy"]) == (
        "checkpoint",
        "zero",
        "random",
    )
    assert s_ckpt["episodes"] == s_zero["episodes"] == 2
    assert s_ckpt["training_seed"] == 3 and s_ckpt["config"]["seed"] == 3
    assert s_zero["checkpoint"] is None and s_zero["training_seed"] is None


def test_protocol_is_recorded(registry, run_dir, tmp_path):
    out = tmp_path / "eval"
    summary = Evaluation(
        EvalRequest("tiny", run_dir / "checkpoint_latest.pt", episodes=2, seed=5, out_dir=out),
        registry,
        progress=False,
    ).run()
    written = json.loads((out / "eval.json").read_text())
    protocol = written["protocol"]
    assert protocol["episodes"] == 2 and protocol["seed"] == 5
    assert protocol["settle_steps"] == 0 and protocol["checkpoint_env_steps"] == 16
    # tiny declares no evaluation protocol: it evaluates where the policy trained, the stage of
    # its 16 training steps (the first: stage_steps 1000)
    assert protocol["stage"] == {"random_pose": False} and protocol["action"] == "mean"
    assert protocol["start"] == written["start"] == "rest"
    commit = protocol["code"]["commit"]
    assert commit is None or len(commit) == 40
    assert "written" not in written and summary["written"][0] == str(out / "eval.json")


def test_baseline_and_bad_policy_arguments(registry):
    with pytest.raises(UsageError, match="valid: checkpoint, zero, random"):
        Evaluation(EvalRequest("tiny", episodes=1, policy="greedy"), registry).run()
    with pytest.raises(UsageError, match="not both"):
        Evaluation(EvalRequest("tiny", "x.pt", episodes=1, policy="zero"), registry).run()


def test_cli_baseline(registry, tmp_path, capsys):
    out = tmp_path / "zero"
    assert (
        main(["eval", "tiny", "--policy", "zero", "--episodes", "1", "--out", str(out), "--json"])
        == 0
    )
    captured = capsys.readouterr()
    assert json.loads(captured.out)["policy"] == "zero"  # stdout: one JSON document
    assert f"written to {out}: eval.json, close.txt" in captured.err
    assert json.loads((out / "eval.json").read_text())["protocol"]["policy"] == "zero"


def test_run_folder_as_checkpoint(registry, run_dir, tmp_path, capsys):
    assert eval_run(run_dir) == 0
    printed = capsys.readouterr().out
    assert f"written to {run_dir / 'eval'}: eval.json, close.txt" in printed
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["eval", "tiny", "--checkpoint", str(empty)]) == 2
    err = capsys.readouterr().err
    assert "folder without checkpoint_latest.pt" in err and "a checkpoint file (.pt)" in err


def test_unwritable_out_is_refused_before_any_episode(registry, run_dir, tmp_path, capsys):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    code = main(["eval", "tiny", "--checkpoint", str(run_dir), "--out", str(blocker / "eval")])
    assert code == 2 and RecordingInfant.log == []
    assert "cannot write to output folder" in capsys.readouterr().err


def test_summary_is_printed_when_writing_fails(registry, run_dir, tmp_path, capsys, monkeypatch):
    def full_disk(self, out_dir):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("devlearn.testing.fake_infant.CloseEvaluator.write_artifacts", full_disk)
    code = eval_run(run_dir, "--json", "--out", str(tmp_path / "eval"))
    captured = capsys.readouterr()
    assert code == 2 and "No space left on device" in captured.err
    assert json.loads(captured.out)["episodes"] == 1


def test_evaluate_takes_a_run_folder(registry, run_dir):
    summary = Evaluation(
        EvalRequest("tiny", run_dir, episodes=1), registry, infant_factory=recording, progress=False
    ).run()
    assert summary["checkpoint"] == str(run_dir / "checkpoint_latest.pt")


class PoseRecordingInfant(RecordingInfant):
    """Also keeps whether each reset asked for a random pose."""

    resets: list = []

    def reset(self, rng, random_pose=False):
        PoseRecordingInfant.resets.append(random_pose)
        super().reset(rng, random_pose)


def test_rest_start_overrides_the_eval_stage(registry, run_dir, tmp_path, capsys):
    def pose_recording(scene, senses=("proprioception",), **kwargs):
        return PoseRecordingInfant(scene, senses, episode_steps=10)

    PoseRecordingInfant.resets = []
    # tiny's first stage, where training starts: the rest pose
    stage = Evaluation(
        EvalRequest("tiny", run_dir, episodes=2),
        registry,
        infant_factory=pose_recording,
        progress=False,
    ).run()
    assert PoseRecordingInfant.resets and not any(PoseRecordingInfant.resets)
    assert stage["protocol"]["start"] == "rest" and stage["start"] == "rest"
    assert stage["protocol"]["start_option"] == "stage"
    PoseRecordingInfant.resets = []
    moved = Evaluation(
        EvalRequest("tiny", run_dir, episodes=2, start="random"),
        registry,
        infant_factory=pose_recording,
        progress=False,
    ).run()
    assert PoseRecordingInfant.resets and all(PoseRecordingInfant.resets)
    assert moved["protocol"]["start"] == "random" and moved["protocol"]["start_option"] == "random"
    PoseRecordingInfant.resets = []
    rest = Evaluation(
        EvalRequest("tiny", run_dir, episodes=2, start="rest"),
        registry,
        infant_factory=pose_recording,
        progress=False,
    ).run()
    assert PoseRecordingInfant.resets and not any(PoseRecordingInfant.resets)
    assert rest["protocol"]["stage"] == {"random_pose": False}
    assert rest["protocol"]["start"] == "rest"
    with pytest.raises(UsageError, match="valid: stage, babybench, rest, random"):
        Evaluation(EvalRequest("tiny", run_dir, episodes=1, start="sideways"), registry).run()
    with pytest.raises(UsageError, match="no such start"):  # a stand-in without starts
        Evaluation(
            EvalRequest("tiny", run_dir, episodes=1, start="babybench"),
            registry,
            infant_factory=pose_recording,
            progress=False,
        ).run()
    out = tmp_path / "rest"
    assert eval_run(run_dir, "--start", "rest", "--out", str(out)) == 0
    assert json.loads((out / "eval.json").read_text())["protocol"]["start"] == "rest"


class StartingInfant(PoseRecordingInfant):
    """A stand-in with the real infant's ``start`` attribute."""

    start = "rest"
    starts: list = []

    def reset(self, rng, random_pose=False):
        StartingInfant.starts.append("random" if random_pose else self.start)
        super().reset(rng, random_pose)


@pytest.mark.parametrize("start", ["babybench", "rest", "random"])
def test_start_options_reach_the_infant_and_the_json(registry, run_dir, tmp_path, start):
    def factory(scene, senses=("proprioception",), **kwargs):
        return StartingInfant(scene, senses, episode_steps=10)

    StartingInfant.starts = []
    out = tmp_path / start
    summary = Evaluation(
        EvalRequest("tiny", run_dir, episodes=2, start=start, out_dir=out),
        registry,
        infant_factory=factory,
        progress=False,
    ).run()
    assert set(StartingInfant.starts) == {start}
    saved = json.loads((out / "eval.json").read_text())
    assert saved["start"] == start and saved["protocol"]["start"] == start
    assert summary["protocol"]["stage"]["random_pose"] == (start == "random")


def test_held_random_baseline_holds_its_actions(registry):
    held, summary = actions_of(registry, None, "held_random")
    again, _ = actions_of(registry, None, "held_random")
    np.testing.assert_array_equal(held, again)  # seeded
    assert summary["policy"] == "held_random"
    assert np.abs(held).max() <= 1.0 and np.ptp(held) > 1.0
    unchanged = (np.diff(held, axis=0) == 0).mean()  # each actuator redraws with p = 1/8
    assert 0.8 < unchanged < 0.95
    iid, _ = actions_of(registry, None, "random")
    assert (np.diff(iid, axis=0) == 0).mean() == 0.0


def test_baseline_config_overrides(registry, tmp_path):
    summary = Evaluation(
        EvalRequest("tiny", episodes=1, policy="zero", overrides=["seed=7"]),
        registry,
        progress=False,
    ).run()
    assert summary["config"]["seed"] == 7
    with pytest.raises(UsageError, match="baselines only"):
        Evaluation(EvalRequest("tiny", tmp_path, episodes=1, overrides=["seed=7"]), registry).run()
    out = tmp_path / "zero"
    assert (
        main(
            [
                "eval",
                "tiny",
                "--policy",
                "zero",
                "--episodes",
                "1",
                "--set",
                "seed=5",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    assert json.loads((out / "eval.json").read_text())["config"]["seed"] == 5


def test_an_undeclared_protocol_evaluates_in_the_stage_the_policy_trained_in(registry, tmp_path):
    from devlearn import EvalProtocol, evaluation_stage

    behavior = TinyBehavior()  # fixed pose for stage_steps (1000), then random poses
    assert behavior.evaluation().stage is None
    assert evaluation_stage(behavior, 0) == {"random_pose": False}
    assert evaluation_stage(behavior, 999) == {"random_pose": False}
    assert evaluation_stage(behavior, 1000) == {"random_pose": True}
    declared = type(
        "Declared", (TinyBehavior,), {"evaluation": lambda self: EvalProtocol(stage={"x": 1})}
    )()
    assert evaluation_stage(declared, 0) == {"x": 1}
    # a baseline evaluates in the stage a default run ends in (tiny: 150,000 steps: random)
    summary = Evaluation(
        EvalRequest("tiny", episodes=1, policy="zero"), registry, progress=False
    ).run()
    assert summary["protocol"]["stage"] == {"random_pose": True} and summary["start"] == "random"


def test_a_checkpoint_is_evaluated_at_its_last_age_or_the_age_given(registry, tmp_path, capsys):
    run = tmp_path / "grew"
    args = ["run", "tiny", "--steps", "32", "--envs", "2", "--out", str(run)]
    assert main([*args, "--set", "infant.growth=3,9"]) == 0  # two iterations: 3, then 9 months
    checkpoint = run / "checkpoint_latest.pt"

    def evaluated(*overrides):
        RecordingInfant.ages = []
        summary = Evaluation(
            EvalRequest("tiny", checkpoint, episodes=1, overrides=[*overrides]),
            registry,
            progress=False,
        ).run()
        age = summary["age_months"]
        assert RecordingInfant.ages == [age] and summary["protocol"]["age_months"] == age
        return age

    assert evaluated() == 9.0  # where it ended
    assert evaluated("infant.age_months=1.5") == 1.5
    assert evaluated("infant.age_months=null") is None  # the default body
    with pytest.raises(UsageError, match="infant.age_months must be between 0 and 24 months"):
        evaluated("infant.age_months=30")
    with pytest.raises(UsageError, match="--set applies to baselines only, and infant.age_m"):
        evaluated("infant.age_months=3", "ppo.gamma=0.9")
    zero = Evaluation(
        EvalRequest("tiny", episodes=1, policy="zero"), registry, progress=False
    ).run()
    assert zero["age_months"] is None
    zero = Evaluation(
        EvalRequest("tiny", episodes=1, policy="zero", overrides=["infant.age_months=2"]),
        registry,
        progress=False,
    ).run()
    assert zero["age_months"] == 2.0
    capsys.readouterr()
    at = ["eval", "tiny", "--checkpoint", str(run), "--episodes", "1"]
    assert main([*at, "--set", "infant.age_months=6"]) == 0
    assert f"written to {run / 'eval_6_months'}" in capsys.readouterr().out
