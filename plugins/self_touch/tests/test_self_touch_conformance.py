"""devlearn's conformance checks and a tiny real training run through the CLI."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from devlearn_self_touch import SelfTouch, SelfTouchConfig

from devlearn.testing import (
    check_behavior,
    check_behavior_class,
    check_curriculum,
    check_gymnasium,
    check_reward_terms,
    registry_for,
)


def _require(module: str, name: str) -> None:
    """Skip unless ``module`` exists and defines ``name`` (the infant and training land later)."""
    if not hasattr(pytest.importorskip(module), name):
        pytest.skip(f"{module}.{name} is not there yet")


def test_class_terms_and_curricula_conform():
    check_behavior_class(SelfTouch)
    check_reward_terms(SelfTouch().reward_terms())
    for variant in ("two_stage", "fixed_only", "random_only"):
        check_curriculum(SelfTouch(SelfTouchConfig(curriculum=variant)).curriculum())
    assert registry_for(SelfTouch).behavior("self_touch") is SelfTouch


@pytest.mark.slow
def test_conformance_on_the_real_infant():
    _require("devlearn.infant", "build_infant")
    shapes = check_behavior(SelfTouch, steps=20)
    assert shapes["body_map"] == (68,)
    assert len(shapes["proprioception"]) == 1


@pytest.mark.slow
def test_tiny_training_run(tmp_path):
    _require("devlearn.infant", "build_infant")
    _require("devlearn.training", "train")
    out = tmp_path / "run"
    cmd = [sys.executable, "-m", "devlearn.cli", "run", "self_touch", "--steps", "512",
           "--envs", "2", "--seed", "1", "--out", str(out)]  # fmt: skip
    subprocess.run(cmd, check=True, timeout=600)
    assert (out / "checkpoint_latest.pt").exists()
    last = json.loads((out / "metrics.jsonl").read_text().splitlines()[-1])
    assert last["step"] >= 512
    evaluation = tmp_path / "eval"
    checkpoint = str(out / "checkpoint_latest.pt")
    cmd = [sys.executable, "-m", "devlearn.cli", "eval", "self_touch", "--checkpoint", checkpoint,
           "--episodes", "1", "--out", str(evaluation)]  # fmt: skip
    subprocess.run(cmd, check=True, timeout=600)
    summary = json.loads((evaluation / "eval.json").read_text())
    assert summary["episodes"] == 1 and summary["parts"] == 34
    assert 0.0 <= summary["score"] <= 1.0
    assert summary["score"] == (summary["coverage_left"] + summary["coverage_right"]) / 68
    assert (evaluation / "self_touch_body_map.png").stat().st_size > 0


def test_gymnasium_conformance():
    # Gymnasium's check_env on devlearn/SelfTouch-v0 (eyes and view rendered), then its
    # vector env; the fixed_only variant too (another curriculum, the same contract)
    check_gymnasium(SelfTouch)
    check_gymnasium(SelfTouch, {"behavior.curriculum": "fixed_only"}, vector_steps=1)
