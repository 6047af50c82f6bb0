"""``devlearn bench``: where a training iteration's time goes (no speed is asserted)."""

from __future__ import annotations

import math

import pytest

from devlearn.bench.iteration import ITERATION_PARTS, iteration_profile
from devlearn.cli.bench import format_table
from devlearn.plugins import PluginRegistry


@pytest.fixture(scope="module")
def profile():
    behavior = PluginRegistry().create("hand_to_mouth")
    return iteration_profile(behavior, ["num_envs=2"], env_steps=10, update_steps=4)


def test_every_part_of_an_iteration_is_timed(profile):
    assert all(math.isfinite(profile[p]) and profile[p] >= 0 for p in ITERATION_PARTS)
    assert profile["total"] == pytest.approx(sum(profile[p] for p in ITERATION_PARTS))
    # hand_to_mouth reads touch and pays rewards; it renders no eyes
    assert profile["touch"] > 0 and profile["rewards"] > 0 and profile["render"] == 0
    for part in ("physics", "inference", "update_forward", "update_backward"):
        assert profile[part] > 0, part
    assert profile["update_us_per_sample"] > 0


def test_the_table_shows_each_parts_share():
    parts = dict.fromkeys(ITERATION_PARTS, 0.5)
    table = format_table({"hand_regard_cnn_iteration_s": {**parts, "total": 5.5}})
    line = table.splitlines()[-1]
    assert line.startswith("hand_regard_cnn, seconds per training iteration (5.50 in all)")
    assert "render 0.50 (9%)" in line and "update_backward 0.50 (9%)" in line


def test_the_evaluation_and_the_cnn_path_have_rows():
    table = format_table(
        {
            "self_touch_eval_s_sequential": 40.0,
            "self_touch_eval_s": 18.5,
            "hand_regard_cnn_train_steps_per_s": 150.0,
            "hand_regard_cnn_update_us_per_sample": 29_000.0,
            "hand_regard_cnn_asym_train_steps_per_s": 250.0,
            "hand_regard_cnn_asym_update_us_per_sample": 15_000.0,
        }
    )
    assert "one env | 40 s |" in table and "automatic envs and workers | 18.5 s |" in table
    assert "| hand-regard training, the paper's CNN (1 thread) | 150 /s |" in table
    assert "| hand-regard CNN update/sample (1 thread) | 29,000 us |" in table
    asymmetric = "the paper's CNN actor, asymmetric critic (1 thread) | 250 /s |"
    assert f"| hand-regard training, {asymmetric}" in table
    assert "asymmetric critic, update/sample (1 thread) | 15,000 us |" in table
