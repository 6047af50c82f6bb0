"""BabyBench's training score: the union per hand over the run's last N training episodes."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from devlearn_self_touch import SelfTouch, SelfTouchConfig
from devlearn_self_touch.evaluation import TrainingScore
from self_touch_fakes import SwappingInfant, make_ctx, train_swapping

from devlearn.testing import load_checkpoint, load_saved_config, registry_for, train


def episode(left=(), right=()) -> np.ndarray:
    """One episode's touched parts, (2, 34): hand 0 is the left, 1 the right."""
    parts = np.zeros((2, 34), bool)
    parts[0, list(left)] = True
    parts[1, list(right)] = True
    return parts


def test_window_is_the_union_per_hand_and_drops_the_oldest_episodes():
    score = TrainingScore(episodes=3)
    assert score.values() == {}  # nothing logged before an episode has ended
    score.add([episode(left=[0, 1]), episode(right=[5])])
    score.add([episode(left=[2], right=[5, 6])])
    assert score.values() == {
        "training_score": (3 + 2) / 68,
        "training_coverage_left": 3.0,
        "training_coverage_right": 2.0,
        "training_score_episodes": 3.0,
    }
    score.add([episode()])  # the first episode (left 0, 1) leaves the window
    assert score.values()["training_score"] == (1 + 2) / 68
    score.add([episode(left=[33])])  # the second (right 5) leaves; the third still has 5
    values = score.values()
    assert (values["training_coverage_left"], values["training_coverage_right"]) == (2.0, 2.0)
    assert values["training_score_episodes"] == 3.0
    # both hands touching the same part count once each: a palm-to-palm contact credits both
    both = TrainingScore(episodes=1)
    both.add([episode(left=[30], right=[30])])
    assert both.values()["training_score"] == 2 / 68


def test_window_state_round_trips_and_a_shorter_window_keeps_the_newest():
    score = TrainingScore(episodes=3)
    history = [episode(left=[p], right=[p + 10]) for p in range(5)]
    score.add(history)
    restored = TrainingScore(episodes=3)
    restored.load_state_dict(score.state_dict())
    assert restored.values() == score.values()
    assert np.array_equal(restored.ordered(), np.stack(history[-3:]))
    for window in (score, restored):  # the same episode leaves both
        window.add([episode()])
    assert (
        restored.values()
        == score.values()
        == {
            "training_score": 4 / 68,
            "training_coverage_left": 2.0,
            "training_coverage_right": 2.0,
            "training_score_episodes": 3.0,
        }
    )
    shorter = TrainingScore(episodes=1)
    shorter.load_state_dict(score.state_dict())
    assert shorter.values()["training_score"] == 0.0  # the newest episode touched nothing


def test_training_evaluator_records_each_episode_for_the_run():
    evaluator = SelfTouch().evaluation().evaluator(True)
    evaluator.record(make_ctx(hand_parts=[(0, 4), (1, 4), (1, 9)], step=0))
    evaluator.end_episode()
    assert np.array_equal(evaluator.episode_record(), episode(left=[4], right=[4, 9]))
    assert SelfTouch().evaluation().evaluator(False).episode_record() is None
    behavior = SelfTouch(SelfTouchConfig(training_score_episodes=7))
    assert behavior.evaluation().run_metrics.episodes == 7
    with pytest.raises(ValueError, match="training_score_episodes must be at least 1"):
        SelfTouchConfig(training_score_episodes=0)


def test_run_logs_the_window_over_all_workers_and_resumes_it(tmp_path):
    """Two envs in two workers, one 20-step episode per env and iteration: env 0's left hand
    touches parts 0-4, env 1's parts 5-9 (SwappingInfant). Each episode touches 5 parts,
    the run's window 10; resumed in process, the window still holds the first episodes."""
    registry = registry_for(SelfTouch)
    out = tmp_path / "run"
    train_swapping(out, ["behavior.training_score_episodes=3"])
    row = json.loads((out / "metrics.jsonl").read_text().splitlines()[-1])
    assert row["metrics/coverage_left"] == 5.0
    assert row["metrics/training_coverage_left"] == 10.0
    assert row["metrics/training_score"] == 10 / 68
    assert row["metrics/training_score_episodes"] == 2.0
    state = load_checkpoint(out / "checkpoint_latest.pt")
    assert state["run_metrics"]["parts"].shape == (2, 2, 5)
    cfg = load_saved_config(out, registry)
    cfg.workers, cfg.total_steps = 0, 80
    train(cfg, registry, resume=out, infant_factory=SwappingInfant, progress=False)
    row = json.loads((out / "metrics.jsonl").read_text().splitlines()[-1])
    assert row["step"] == 80
    assert row["metrics/training_score_episodes"] == 3.0  # 2 saved + 2 new, window of 3
    assert row["metrics/training_coverage_left"] == 10.0


@pytest.mark.slow
def test_tiny_real_run_logs_the_training_score(tmp_path):
    """The real infant: 4 envs x 64 decisions x 5 physics steps per iteration, so each env
    ends its first 1,000-step episode in the 4th iteration."""
    out = tmp_path / "run"
    cmd = [sys.executable, "-m", "devlearn.cli", "run", "self_touch", "--steps", "5120",
           "--envs", "4", "--workers", "0", "--seed", "1", "--set", "torch_threads=1",
           "--out", str(out)]  # fmt: skip
    subprocess.run(cmd, check=True, timeout=900)
    rows = [json.loads(line) for line in (out / "metrics.jsonl").read_text().splitlines()]
    last = rows[-1]
    assert last["metrics/training_score_episodes"] == 4.0
    assert 0.0 <= last["metrics/training_score"] <= 1.0
    parts = last["metrics/training_coverage_left"] + last["metrics/training_coverage_right"]
    assert last["metrics/training_score"] == parts / 68
    assert "metrics/training_score" not in rows[0]  # no episode had ended yet
