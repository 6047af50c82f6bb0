"""The offline analyses of self-touch's published evaluations (devlearn_self_touch.analysis):
the imbalance's split on an evaluation built here, checked by hand, and the checkpoint table
against the committed tables of results/self_touch/i20, byte for byte."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from devlearn_self_touch.analysis import balance, checkpoint_table

from devlearn import UsageError

ROOT = Path(__file__).resolve().parents[3]
I20 = ROOT / "results" / "self_touch" / "i20"

# per episode, how many parts each hand touched: d = L - R = 6, 1, -1, 7, 3
LEFT, RIGHT = (7, 4, 2, 8, 3), (1, 3, 3, 1, 0)


def _eval_json(tmp_path: Path) -> Path:
    """An eval.json whose episodes touch LEFT / RIGHT parts, nested as a sweep nests it."""
    episodes = [
        {"left": list(range(n_left)), "right": list(range(10, 10 + n_right))}
        for n_left, n_right in zip(LEFT, RIGHT)
    ]
    path = tmp_path / "eval.json"
    path.write_text(json.dumps({"episodes": 5, "evaluation": {"episode_parts": episodes}}))
    return path


def test_the_imbalance_splits_into_preference_and_spread_as_computed_by_hand(tmp_path, capsys):
    path = _eval_json(tmp_path)
    row = balance.main([str(path)])[str(path)]
    # mean |d| = 18/5; the preference mean d = 16/5; without it, |d - round(3.2)| =
    # (3, 2, 4, 4, 0) -> 13/5 (not |d - 3.2| -> 13.2/5); |d| <= 3 in 3 of the 5 (|3| counts)
    assert row["episodes"] == 5 and row["left"] == 24 / 5 and row["right"] == 8 / 5
    assert row["balance"] == pytest.approx(18 / 5) and row["preference"] == pytest.approx(16 / 5)
    assert row["without_preference"] == pytest.approx(13 / 5)
    assert row["bonus_paid"] == pytest.approx(3 / 5)
    assert row["corr"] == pytest.approx(np.corrcoef(LEFT, RIGHT)[0, 1])
    # shuffled hands: the mean of |L_i - R_j| over all 25 pairs is 84/25, up to 200 shuffles
    assert row["independent"] == pytest.approx(84 / 25, abs=0.15)
    printed = capsys.readouterr().out.splitlines()
    assert printed[2] == (
        f"| {path} | 4.80 | 1.60 | 3.60 | +3.20 | 2.60 | {row['corr']:.2f} | "
        f"{row['independent']:.2f} | 0.60 |"
    )


def test_a_constant_preference_leaves_no_imbalance_without_it_and_a_signed_mean():
    # the right hand always touches 4 more parts: all imbalance is the preference
    episodes = [{"left": [0] * n, "right": [0] * (n + 4)} for n in (1, 5, 9)]
    row = balance.decompose(episodes)
    assert row["preference"] == -4 and row["balance"] == 4 and row["without_preference"] == 0
    assert row["bonus_paid"] == 0 and row["corr"] == pytest.approx(1.0)
    rows = {"a": row, "b": {**row, "preference": 2.0}}
    assert balance.table(rows).splitlines()[-1].split(" | ")[4] == "3.00"  # mean of |pref|


def test_an_evaluation_without_episode_parts_is_refused_with_what_is_valid(tmp_path):
    path = tmp_path / "eval.json"
    path.write_text(json.dumps({"episodes": 4, "score": 0.5}))
    with pytest.raises(UsageError, match="devlearn eval self_touch"):
        balance.main([str(path)])
    with pytest.raises(UsageError, match="empty"):
        balance.decompose([])


@pytest.mark.parametrize(
    ("runs", "table"),
    [
        ([], "checkpoint_table_8M.md"),
        (["two_stage_s1", "per_env_s1"], "checkpoint_table_per_env.md"),
    ],
)
def test_the_checkpoint_tables_are_the_committed_ones(runs, table):
    markdown = checkpoint_table.main([*runs, "--folder", str(I20)])
    assert markdown == (I20 / table).read_text()


def test_a_run_without_evaluated_checkpoints_is_refused(tmp_path):
    (tmp_path / "two_stage_s1").mkdir()
    with pytest.raises(UsageError, match="at_<steps>/eval.json"):
        checkpoint_table.table(tmp_path, [])
    with pytest.raises(UsageError, match="no two_stage_s<N> run"):
        checkpoint_table.table(tmp_path / "two_stage_s1", [])
