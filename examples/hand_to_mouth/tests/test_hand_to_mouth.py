"""Tests of the example plugin, written only against devlearn's public API."""

from __future__ import annotations

import json
import subprocess
import sys
from importlib.metadata import entry_points

import pytest
from devlearn_hand_to_mouth import HandToMouth
from devlearn_hand_to_mouth.behavior import ActionCost, MouthContact

from devlearn import StepContext
from devlearn.testing import Play, check_behavior, check_gymnasium, facts_of, registry_for


def _ctx(contact: bool, energy: float = 0.0) -> StepContext:
    facts = {"mouth_contact": contact, "action_energy": energy}
    return StepContext(None, {}, facts, step=0, last_step=False)


def test_entry_point_is_installed():
    names = {ep.name: ep.value for ep in entry_points(group="devlearn")}
    assert names["hand_to_mouth"] == "devlearn_hand_to_mouth.plugin"


def test_registry_finds_behavior():
    assert registry_for(HandToMouth).behavior("hand_to_mouth") is HandToMouth


def test_mouth_contact_pays_bonus_once_per_episode():
    term = MouthContact(contact_reward=1.0, first_bonus=5.0)
    assert term(_ctx(False)) == 0.0
    assert term(_ctx(True)) == 6.0
    assert term(_ctx(True)) == 1.0
    term.reset()
    assert term(_ctx(True)) == 6.0


def test_action_cost_is_negative_energy():
    assert ActionCost(weight=0.01)(_ctx(False, energy=0.25)) == -0.25


@pytest.mark.slow
def test_the_action_of_each_environment_is_its_own():
    """Two environments played in one batch: each env's hooks keep its own last action, so the
    action-cost fact is each env's (facts written per environment, ``devlearn.per_env``)."""
    with Play(HandToMouth(), 2) as envs:
        envs.reset()
        envs.step([[0.0] * envs.action_dim, [0.5] * envs.action_dim])
        energies = [facts_of(b, i)["action_energy"] for b, i in zip(envs.behaviors, envs.infants)]
    assert energies == [0.0, 0.25]


def test_conformance():
    shapes = check_behavior(HandToMouth, steps=20)
    assert set(shapes) == {"proprioception"}


@pytest.mark.slow
def test_tiny_training_run(tmp_path):
    out = tmp_path / "run"
    cmd = [
        sys.executable,
        "-m",
        "devlearn.cli",
        "run",
        "hand_to_mouth",
        "--steps",
        "512",
        "--envs",
        "2",
        "--seed",
        "1",
        "--out",
        str(out),
    ]
    subprocess.run(cmd, check=True, timeout=600)
    assert (out / "checkpoint_latest.pt").exists()
    lines = (out / "metrics.jsonl").read_text().splitlines()
    assert json.loads(lines[-1])["step"] >= 512


def test_gymnasium_conformance():
    # devlearn/HandToMouth-v0 passes Gymnasium's check_env, and its vector env steps
    check_gymnasium(HandToMouth)


def test_the_stall_diagnostic_tells_a_still_failure_from_a_moving_one():
    """Issue #54 item 3's diagnostic (``python -m devlearn_hand_to_mouth.stalls``): an untrained
    policy's mean action (the committed test checkpoint) fails both episodes with the joints
    still over the last second, a stall; with noise of spread 3 it fails moving."""
    from pathlib import Path

    from devlearn_hand_to_mouth.stalls import STALL_SPEED, stalls

    checkpoint = Path(__file__).parents[3] / "tests/training/data/hand_to_mouth_shared.pt"
    still = stalls(str(checkpoint), episodes=2, noise=0.0)
    assert (still["failed"], still["failed_stalled"]) == (2, 2)
    assert max(still["failed_end_speed"]) < STALL_SPEED
    moving = stalls(str(checkpoint), episodes=2, noise=3.0)
    assert (moving["failed"], moving["failed_stalled"]) == (2, 0)
    assert min(moving["failed_end_speed"]) > 1.0
