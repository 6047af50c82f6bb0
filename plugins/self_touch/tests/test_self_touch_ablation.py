"""The ablation table reads each run's config and eval JSON."""

from __future__ import annotations

import json

import pytest
from devlearn_self_touch.ablation import ablation_table, main


def _run(tmp_path, name, curriculum, score, with_eval=True, seed=1, left=20):
    run = tmp_path / name
    (run / "eval").mkdir(parents=True)
    behavior = {"curriculum": curriculum, "fixed_pose_steps": 200_000}
    config = {"total_steps": 400_000, "seed": seed, "behavior": behavior}
    (run / "config.json").write_text(json.dumps(config))
    if with_eval:
        result = {
            "episodes": 100,
            "coverage_left": left,
            "coverage_right": 22,
            "coverage_total": 25,
            "balance": 2,
            "score": score,
        }
        (run / "eval" / "eval.json").write_text(json.dumps(result))
    return run


def test_table_has_a_row_per_run(tmp_path):
    runs = [_run(tmp_path, "a", "fixed_only", 0.5), _run(tmp_path, "b", "two_stage", 0.625)]
    lines = ablation_table(runs).splitlines()
    assert len(lines) == 4  # one seed per variant: no summary table
    assert lines[2] == "| a | fixed_only | 400,000 | 1 | 100 | 20 | 22 | 25 | 2 | 0.50 |"
    assert "two_stage (fixed pose for 200,000 steps)" in lines[3] and lines[3].endswith("0.62 |")


def test_missing_eval_says_which_command_makes_it(tmp_path, capsys):
    run = _run(tmp_path, "c", "random_only", 0.1, with_eval=False)
    with pytest.raises(SystemExit) as exit_info:
        main([str(run)])
    assert exit_info.value.code == 2
    assert "devlearn eval self_touch --checkpoint" in capsys.readouterr().err


def test_seeds_of_one_variant_are_summarised(tmp_path):
    runs = [
        _run(tmp_path, "a1", "random_only", 0.5, seed=1, left=20),
        _run(tmp_path, "a2", "random_only", 0.75, seed=2, left=25),
        _run(tmp_path, "b1", "fixed_only", 0.25, seed=1, left=10),
    ]
    lines = ablation_table(runs).splitlines()
    summary = lines[lines.index("") + 1 :]
    assert summary[0].startswith("| curriculum | steps | seeds | coverage_left mean (min-max)")
    assert summary[2] == (
        "| random_only | 400,000 | 2 | 22.5 (20-25) | 22.0 (22-22) | 25.0 (25-25) | 2.0 (2-2) "
        "| 0.62 (0.50-0.75) |"
    )
    assert summary[3].startswith("| fixed_only | 400,000 | 1 | 10.0 (10-10) |")
