"""``devlearn bench``: the figures it reports and their table (no speed is asserted here)."""

from __future__ import annotations

import math

from devlearn.bench import bench_infant
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
    assert "| self-touch env steps/s (1 process) | 1,234 /s | 400-600 | >= 2500 |" in table
    assert "| touch per step (dense N x 3 vector) | 0.123 ms | 3 | <= 0.2 |" in table
    assert "failed (see stderr)" in table
    assert len(table.splitlines()) == 4 + 3  # title, blank, header, rule, three rows
    assert len({key for key, *_ in ROWS}) == len(ROWS)
