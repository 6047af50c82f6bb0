"""``devlearn report``: variants grouped by config, t-intervals over seeds, baselines, errors."""

from __future__ import annotations

import json

import pytest
from scipy import stats

from devlearn.cli import main
from devlearn.errors import UsageError
from devlearn.report import write_report


def fake_eval(folder, score, seed, behavior="self_touch", policy="checkpoint", max_std=1.0):
    folder.mkdir(parents=True)
    config = {"seed": seed, "total_steps": 100, "out_dir": f"runs/{folder.name}",
              "behavior": {"max_std": max_std, "touch_threshold": 0.1}}
    summary = {
        "episodes": 100, "score": score, "coverage_total": 30 * score,
        "episode_score_mean": score / 2, "episode_score_std": 0.1,
        "part_touch_steps": {"left": {"head": 3}},
        "behavior": behavior, "policy": policy, "checkpoint_env_steps": 100,
        "training_seed": seed if policy == "checkpoint" else None, "config": config,
        "protocol": {"episodes": 100, "seed": 0, "settle_steps": 10, "headline": "score",
                     "criteria": {"hand_touch": "..."}},
    }
    (folder / "eval.json").write_text(json.dumps(summary))
    return folder


@pytest.fixture
def three_seeds(tmp_path):
    runs = [fake_eval(tmp_path / f"seed{s}" / "eval", v, s)
            for s, v in ((1, 0.90), (2, 0.96), (3, 0.81))]
    fake_eval(tmp_path / "baseline_zero", 0.2, 0, policy="zero")
    fake_eval(tmp_path / "baseline_random", 0.3, 0, policy="random")
    return [r.parent for r in runs]  # run folders holding evaluation folders


def test_three_seeds_give_scipys_interval(three_seeds, tmp_path):
    result = write_report(three_seeds, tmp_path / "report")
    scores = [0.90, 0.96, 0.81]
    low, high = stats.t.interval(0.95, 2, loc=sum(scores) / 3, scale=stats.sem(scores))
    cell = result["table"]["score"]["trained"]
    assert cell["n"] == 3 and cell["mean"] == pytest.approx(sum(scores) / 3)
    assert (cell["ci_low"], cell["ci_high"]) == (pytest.approx(low), pytest.approx(high))
    assert result["metrics"][0] == "score"  # the headline first
    assert "episode_score_std" not in result["table"]  # per-episode spread is not a metric
    assert "part_touch_steps.left.head" not in result["table"]
    # Baselines found beside the run folders, under the same metrics.
    assert result["table"]["score"]["zero baseline"]["mean"] == 0.2
    assert result["columns"]["random baseline"]["kind"] == "baseline"
    markdown = (tmp_path / "report" / "report.md").read_text()
    assert f"{sum(scores) / 3:.3g} [{low:.3g}, {high:.3g}]" in markdown
    assert "zero baseline (n=1)" in markdown
    png = (tmp_path / "report" / "report.png").read_bytes()
    assert png[:4] == b"\x89PNG"
    write_report(three_seeds, tmp_path / "again")
    assert (tmp_path / "again" / "report.png").read_bytes() == png  # deterministic


def test_variants_are_the_config_keys_that_differ(tmp_path):
    paths = [fake_eval(tmp_path / f"a{s}", 0.5 + s / 10, s, max_std=0.0) for s in (1, 2)]
    paths += [fake_eval(tmp_path / f"b{s}", 0.9, s, max_std=1.0) for s in (1,)]
    result = write_report(paths, tmp_path / "report")
    assert set(result["columns"]) == {"behavior.max_std=0.0", "behavior.max_std=1.0"}
    assert result["table"]["score"]["behavior.max_std=0.0"]["n"] == 2
    assert any("single seed" in n for n in result["notes"])
    assert "single seed" in (tmp_path / "report" / "report.md").read_text()


def test_bad_input(tmp_path, three_seeds, capsys):
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(UsageError, match="no eval.json"):
        write_report([empty], tmp_path / "r")
    other = fake_eval(tmp_path / "hr" / "eval", 0.5, 1, behavior="hand_regard")
    with pytest.raises(UsageError, match="different behaviours mixed"):
        write_report([*three_seeds, other], tmp_path / "r")
    assert main(["report", str(empty), "--out", str(tmp_path / "r")]) == 2
    errors = [line for line in capsys.readouterr().err.splitlines() if "error" in line]
    assert len(errors) == 1 and errors[0].startswith("devlearn: error: ")  # one line
    assert main(["report", *map(str, three_seeds), "--out", str(tmp_path / "r")]) == 0
    assert "| `score` |" in capsys.readouterr().out
