"""``devlearn bench``: the PPO update cost of both layouts (no speed is asserted)."""

from __future__ import annotations

import math

from devlearn.bench.learner import bench_update, run_config
from devlearn.plugins import PluginRegistry


def test_update_benchmark_reports_both_layouts():
    behavior = PluginRegistry().create("hand_to_mouth")
    shared = bench_update(behavior, "shared", num_envs=4, num_steps=8, repeats=1, threads=1)
    separate = bench_update(behavior, "separate", num_envs=4, num_steps=8, repeats=1, threads=1)
    for figures in (shared, separate):
        assert math.isfinite(figures["update_us_per_sample"]) and figures["threads"] == 1
        assert figures["inference_ms_per_step"] > 0
    # one body instead of two: fewer than the separate networks' parameters
    assert shared["parameters"] < separate["parameters"]


def test_a_rollout_longer_than_the_behaviours_own_fits_the_storage():
    # devlearn bench collects 128 steps per env; the storage was built for the behaviour's
    # own ppo.num_steps_per_env (64 since the learner's defaults) and overflowed
    behavior = PluginRegistry().create("hand_to_mouth")
    own = run_config(behavior, []).ppo.num_steps_per_env
    figures = bench_update(behavior, "separate", 2, num_steps=own + 8, repeats=1, threads=1)
    assert math.isfinite(figures["update_us_per_sample"])


def test_sb3s_update_is_measured_on_a_rollout_of_the_same_size():
    """Issue #54: SB3's PPO update beside ours on the same rollout size and settings; its
    network is SB3's flat MLP of the behaviour's hidden sizes (fewer parameters than ours)."""
    import pytest

    pytest.importorskip("stable_baselines3")
    from devlearn.bench.learner import bench_sb3_update

    behavior = PluginRegistry().create("hand_to_mouth")
    figures = bench_sb3_update(behavior, num_envs=2, num_steps=8, repeats=1, threads=1)
    assert figures is not None and math.isfinite(figures["update_us_per_sample"])
    ours = bench_update(behavior, "separate", 2, num_steps=8, repeats=1, threads=1)
    spec = behavior.network()
    hidden = [*spec.fusion_dims, *spec.trunk_dims]
    # SB3's networks: one flat MLP each for policy and value, with a log-std per action: since
    # issue #54 the core default's too
    assert hidden and figures["parameters"] == ours["parameters"]
