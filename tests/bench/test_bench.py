"""``devlearn bench``: the figures it reports and their table (no speed is asserted here)."""

from __future__ import annotations

import math

import pytest

from devlearn.bench.infant import bench_infant
from devlearn.cli.bench import ROWS, format_table


def test_bench_infant_reports_every_sense_cost():
    result = bench_infant(steps=40, frames=3)
    for key in (
        "build_s",
        "physics_ms_per_step",
        "touch_ms_per_step",
        "touch_sparse_ms_per_step",
        "proprioception_ms_per_step",
        "render_ms_per_frame",
    ):
        assert math.isfinite(result[key]) and result[key] > 0, key
    assert result["touch_sensors"] > 4500


def test_table_lists_known_figures_and_failures():
    result = {
        "date": "2026-11-23",
        "machine": "x86_64, 2 cores",
        "self_touch_steps_per_s": 1234.5,
        "touch_ms_per_step": 0.123,
        "hand_regard_train_steps_per_s": None,
    }
    table = format_table(result)
    assert "| self-touch env steps/s (1 process) | 1,234 /s | 283 | >= 4000 |" in table
    assert "| touch per step (dense N x 3 vector) | 0.123 ms | 3 | - |" in table
    assert "failed (see stderr)" in table
    assert len(table.splitlines()) == 4 + 3  # title, blank, header, rule, three rows
    assert len({key for key, *_ in ROWS}) == len(ROWS)


def test_ceiling_and_breakdown_of_a_step():
    from devlearn_self_touch import SelfTouch

    from devlearn.bench.ceiling import BREAKDOWN_PARTS, env_breakdown, physics_ceiling

    assert physics_ceiling("crib", 30) > 0
    parts = env_breakdown(SelfTouch(), steps=30)
    assert set(parts) == {*BREAKDOWN_PARTS, "total"}
    assert all(parts[p] >= 0 for p in BREAKDOWN_PARTS)
    assert parts["physics"] > 0 and parts["touch"] > 0 and parts["rewards"] > 0
    assert parts["eyes"] == 0.0  # self_touch reads no eyes
    assert math.isclose(parts["total"], sum(parts[p] for p in BREAKDOWN_PARTS))


def test_table_shows_fractions_and_breakdowns():
    result = {
        "self_touch_fraction_of_ceiling": 0.2345,
        "self_touch_breakdown_ms": {"physics": 0.05, "touch": 0.01, "total": 0.06},
    }
    table = format_table(result)
    assert "| self-touch env / crib physics | 23% | 8% | >= 20% |" in table
    assert "self_touch, ms per step (0.060 in all): physics 0.050, touch 0.010" in table


def test_batched_and_per_env_observation_paths_are_measured_in_one_run():
    from devlearn_self_touch import SelfTouch

    from devlearn.bench.ceiling import observations_old_and_new, with_per_env_observations

    behavior = SelfTouch()
    old = with_per_env_observations(behavior)
    assert type(old).facts is not SelfTouch.facts and type(old).observe is not SelfTouch.observe
    assert old.config == behavior.config and old.name == "self_touch"
    figures = observations_old_and_new(behavior, steps=20, vec_steps=2)
    rates = {
        f"self_touch_{key}{suffix}"
        for key in ("steps_per_s", "vec_steps_per_s_in_process")
        for suffix in ("", "_per_env_observations")
    }
    assert set(figures) == rates | {"self_touch_breakdown_per_env_observations_ms"}
    assert all(figures[key] > 0 for key in rates)
    table = format_table(figures)
    assert "self_touch_per_env_observations, ms per step" in table


def test_bench_reports_cli_start_up():
    from devlearn.bench.run import STARTUP_COMMANDS, cli_startup_s

    assert set(STARTUP_COMMANDS) == {"help", "plugins", "config", "info"}
    assert cli_startup_s(["--help"], repeats=1) > 0
    table = format_table({"startup_help_s": 0.84})
    assert "| start-up: devlearn --help | 0.84 s | - | < 1.5 |" in table


def test_the_gymnasium_vector_env_is_measured_beside_devvecenv():
    from devlearn.bench.speed import bench_gym_vec_env

    figures = bench_gym_vec_env("self_touch", num_envs=2, workers=0, steps=3)
    assert set(figures) == {
        "gym_vec_steps_per_s",
        "gym_vec_devlearn_steps_per_s",
        "gym_vec_fraction_of_devlearn",
    }
    ratio = figures["gym_vec_steps_per_s"] / figures["gym_vec_devlearn_steps_per_s"]
    assert figures["gym_vec_fraction_of_devlearn"] == ratio > 0
    table = format_table({**figures, "gym_vec_fraction_of_devlearn": 0.93})
    assert "| Gymnasium vector env / DevVecEnv | 93% | - | >= 85% |" in table


def test_the_training_rate_is_the_runs_steps_over_its_seconds():
    """``devlearn bench``'s end-to-end training figure (issue #54 item 5): the steps of the
    iterations after the first over their seconds, not the mean of the iterations' rates (a
    slow thread-plan probe iteration weighs by its time)."""
    from devlearn.bench.speed import training_rate

    rows = [
        {"step": 5120, "collect_s": 3.0, "update_s": 1.0},  # start-up: left out
        {"step": 10240, "collect_s": 0.5, "update_s": 0.2},
        {"step": 15360, "collect_s": 0.5, "update_s": 1.8},  # a slow probe
        {"step": 20480, "collect_s": 0.5, "update_s": 0.2},
    ]
    assert training_rate(rows) == pytest.approx(3 * 5120 / 3.7)
    assert training_rate(rows[:1]) == pytest.approx(5120 / 4.0)
