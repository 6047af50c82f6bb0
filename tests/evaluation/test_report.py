"""``devlearn report``: variants grouped by config, t-intervals over seeds, baselines, errors."""

from __future__ import annotations

import json

import pytest
from scipy import stats

from devlearn.api.errors import UsageError
from devlearn.cli import main
from devlearn.evaluation.report import write_report


def fake_eval(folder, score, seed, behavior="self_touch", policy="checkpoint", max_std=1.0, **more):
    folder.mkdir(parents=True)
    config = {
        "seed": seed,
        "total_steps": 100,
        "out_dir": f"runs/{folder.name}",
        "behavior": {"max_std": max_std, "touch_threshold": 0.1},
    }
    summary = {
        "episodes": 100,
        "score": score,
        "coverage_total": 30 * score,
        "episode_score_mean": score / 2,
        "episode_score_std": 0.1,
        "part_touch_steps": {"left": {"head": 3}},
        "behavior": behavior,
        "policy": policy,
        "checkpoint_env_steps": 100,
        "training_seed": seed if policy == "checkpoint" else None,
        "config": config,
        "protocol": {
            "episodes": 100,
            "seed": 0,
            "settle_steps": 10,
            "headline": "score",
            "criteria": {"hand_touch": "..."},
        },
        **more,
    }
    (folder / "eval.json").write_text(json.dumps(summary))
    return folder


@pytest.fixture
def three_seeds(tmp_path):
    runs = [
        fake_eval(tmp_path / f"seed{s}" / "eval", v, s)
        for s, v in ((1, 0.90), (2, 0.96), (3, 0.81))
    ]
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
    # the headline first, as the per-episode mean (self-touch's headline), not the union score
    assert result["metrics"][0] == "episode_score_mean" and result["metrics"][1] == "score"
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


def test_policies_of_another_learner_are_a_variant_of_their_own(tmp_path):
    paths = [fake_eval(tmp_path / f"ours{s}", 0.5, s) for s in (1, 2)]
    for s in (1, 2):  # the same config, trained by SB3 (a scripted policy's eval JSON)
        folder = fake_eval(tmp_path / f"sb3{s}", 0.2, s)
        summary = json.loads((folder / "eval.json").read_text())
        (folder / "eval.json").write_text(json.dumps({**summary, "learner": "sb3_ppo"}))
        paths.append(folder)
    result = write_report(paths, tmp_path / "report")
    assert set(result["columns"]) == {"learner=devlearn_ppo", "learner=sb3_ppo"}
    assert result["table"]["score"]["learner=sb3_ppo"]["mean"] == 0.2


def test_a_policy_and_a_baseline_evaluated_at_several_ages_are_a_column_per_age(tmp_path):
    # issue #41: each seed's policy evaluated at its own age and at another one
    paths = [
        fake_eval(tmp_path / f"seed{s}" / folder, score, s, age_months=age)
        for s in (1, 2)
        for folder, score, age in (("eval", 0.6, 18.0), ("eval_6_months", 0.3, 6.0))
    ]
    for age in (6.0, 18.0):
        fake_eval(tmp_path / f"random_{age:g}", age / 100, 0, policy="random", age_months=age)
    result = write_report(paths, tmp_path / "report")
    assert result["notes"] == []  # two ages of one seed are not one seed evaluated twice
    table = result["table"]["score"]
    assert table["eval.age_months=18.0"]["values"] == [0.6, 0.6]
    assert table["eval.age_months=6.0"]["values"] == [0.3, 0.3]
    assert table["random (6 months) baseline"]["values"] == [0.06]
    assert table["random (18 months) baseline"]["values"] == [0.18]
    assert result["columns"]["random (6 months) baseline"]["kind"] == "baseline"


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


def test_paper_columns_beside_ours(tmp_path):
    """The paper's figures come per variant config; metrics it gives no figure for show -."""
    paths = [fake_eval(tmp_path / f"a{s}", 0.5 + s / 10, s, max_std=0.0) for s in (1, 2)]
    paths += [fake_eval(tmp_path / f"b{s}", 0.9, s, max_std=1.0) for s in (1, 2)]

    def paper(behavior, config):
        assert behavior == "self_touch"
        if config["behavior"]["max_std"] == 0.0:
            return "paper: A", {"score": 0.85, "coverage_total": 32}
        return "paper: B", {"score": 0.72}

    result = write_report(paths, tmp_path / "report", paper)
    assert result["columns"]["paper: A"] == {"kind": "paper", "seeds": [], "paths": []}
    assert result["table"]["score"]["paper: A"]["mean"] == 0.85
    assert result["table"]["score"]["paper: B"]["mean"] == 0.72
    assert result["table"]["coverage_total"]["paper: B"]["mean"] is None
    md = (tmp_path / "report" / "report.md").read_text()
    header = next(line for line in md.splitlines() if line.startswith("| metric"))
    assert header.endswith("| paper: A | paper: B |")  # after the baselines, without n=
    score_row = next(line for line in md.splitlines() if line.startswith("| `score`"))
    assert score_row.endswith("| 0.85 | 0.72 |")
    coverage_row = next(line for line in md.splitlines() if line.startswith("| `coverage_total`"))
    assert coverage_row.endswith("| 32 | - |")
    assert (tmp_path / "report" / "report.png").read_bytes()[:4] == b"\x89PNG"
    # Without a source of paper figures (or a behaviour that has none): no paper column.
    assert not any(c.startswith("paper") for c in write_report(paths, tmp_path / "r2")["columns"])
    no_figures = write_report(paths, tmp_path / "r3", lambda behavior, config: None)
    assert not any(c.startswith("paper") for c in no_figures["columns"])


def test_cli_report_shows_the_behaviours_paper_figures(three_seeds, tmp_path, capsys):
    """`devlearn report` asks the installed behaviour (self_touch: Table I for two-stage)."""
    assert main(["report", *map(str, three_seeds), "--out", str(tmp_path / "r")]) == 0
    out = capsys.readouterr().out
    assert "paper: two-stage, 8M (Tables I-II)" in out
    score_row = next(line for line in out.splitlines() if line.startswith("| `score`"))
    assert score_row.endswith("| 0.85 |")


@pytest.mark.parametrize(
    ("behavior", "eval_json", "config"),
    [
        ("self_touch", "results/self_touch/i20/two_stage_s1/at_8001536/eval.json", {}),
        ("self_touch", None, {"behavior": {"curriculum": "fixed_only"}}),
        ("self_touch", None, {"behavior": {"curriculum": "random_only"}}),
        ("hand_regard", "results/hand_regard/eval/eval.json", {}),
    ],
)
def test_paper_figures_name_real_metrics(behavior, eval_json, config):
    """Every figure a behaviour gives for the paper is a metric its evaluations report (a
    misnamed key would leave its column empty)."""
    from pathlib import Path

    from devlearn.evaluation.report import _metrics
    from devlearn.plugins import PluginRegistry

    root = Path(__file__).resolve().parents[2]
    if eval_json is None:  # the self-touch metrics are the same whatever the curriculum
        eval_json = "results/self_touch/i20/two_stage_s1/at_8001536/eval.json"
    label, figures = PluginRegistry(disabled=()).behavior(behavior).about.paper_figures(config)
    metrics = _metrics(json.loads((root / eval_json).read_text()))
    assert label.startswith("paper") and figures
    assert set(figures) <= set(metrics)


def test_baselines_are_counted_not_seeded_and_single_runs_get_no_caps(
    three_seeds, tmp_path, monkeypatch
):
    from matplotlib.figure import Figure

    drawn = []
    monkeypatch.setattr(Figure, "savefig", lambda self, *a, **k: drawn.append(self))
    result = write_report(three_seeds, tmp_path / "report")
    markdown = (tmp_path / "report" / "report.md").read_text()
    assert "None" not in markdown
    assert "- **zero baseline**: 1 evaluation of an untrained policy (no seed) from" in markdown
    assert "- **trained**: seeds [1, 2, 3] from" in markdown
    (fig,) = drawn
    columns = list(result["columns"])
    for ax in fig.axes:
        bars = [c for c in ax.containers if type(c).__name__ == "BarContainer"]
        errors = [c for c in ax.containers if type(c).__name__ == "ErrorbarContainer"]
        assert len(bars) == 1 and len(bars[0]) == len(columns)
        # one interval: the three seeds; the single baseline evaluations have none
        assert len(errors) == 1 and len(errors[0].lines[2][0].get_segments()) == 1


def test_baselines_beside_an_evaluation_are_taken_only_of_its_behaviour(tmp_path):
    """A runs/ folder holding another behaviour's baseline (the README's hand-regard
    held_random) beside a self-touch evaluation: the report takes self-touch's only."""
    run = fake_eval(tmp_path / "runs" / "st" / "eval", 0.5, 1)
    fake_eval(tmp_path / "runs" / "st_zero", 0.2, 0, policy="zero")
    fake_eval(tmp_path / "runs" / "hr_held", 0.0, 0, behavior="hand_regard", policy="random")
    result = write_report([run, tmp_path / "runs" / "st_zero"], tmp_path / "report")
    assert set(result["columns"]) == {"trained", "zero baseline"}


def test_configs_saved_before_and_after_a_key_rename_are_one_variant(tmp_path, capsys):
    """Issue #31 moved `behavior.weight_balance` to `behavior.rewards.balance.weight`: the
    CLI compares configs as runs load them, so two seeds saved the old way and one saved the
    new way are one recipe, and a changed weight (either way of saving) is another."""
    from pathlib import Path

    from devlearn.config.run_config import from_dict, to_dict
    from devlearn.plugins import PluginRegistry

    root = Path(__file__).resolve().parents[2]
    old = json.loads(
        (root / "results/self_touch/i30/curriculum/two_stage/seed=1/config.json").read_text()
    )
    assert "weight_balance" in old["behavior"] and "rewards" not in old["behavior"]
    new = to_dict(from_dict(old, PluginRegistry().behavior("self_touch")))
    assert "weight_balance" not in new["behavior"] and "rewards" in new["behavior"]
    no_balance = json.loads(json.dumps(new))
    no_balance["behavior"]["rewards"]["balance"]["weight"] = 0.0
    no_balance_old = {**old, "behavior": {**old["behavior"], "weight_balance": 0.0}}
    runs = []
    for name, seed, config in [
        ("old1", 1, old),
        ("old2", 2, old),
        ("new3", 3, new),
        ("off1", 1, no_balance),
        ("off2", 2, no_balance_old),
    ]:
        folder = fake_eval(tmp_path / name / "eval", 0.5 + seed / 10, seed)
        data = json.loads((folder / "eval.json").read_text())
        data["config"] = {**config, "seed": seed, "out_dir": f"runs/{name}"}
        (folder / "eval.json").write_text(json.dumps(data))
        runs.append(str(folder))
    assert main(["report", *runs, "--out", str(tmp_path / "r")]) == 0
    out = capsys.readouterr().out
    markdown = (tmp_path / "r" / "report.md").read_text()
    assert markdown in out
    listed = {
        line.split("**")[1]: line.split("seeds ")[1].split(" from")[0]
        for line in markdown.splitlines()
        if line.startswith("- **behavior.")
    }
    assert listed == {
        "behavior.rewards.balance.weight=1.0": "[3, 1, 2]",  # new3/ sorts before old1/
        "behavior.rewards.balance.weight=0.0": "[1, 2]",
    }
    # as saved (no loader), the old and new files would have been told apart
    columns = write_report(runs, tmp_path / "raw")["columns"]
    assert len([c for c in columns if not c.endswith("baseline")]) > 2


def test_a_fifo_named_eval_json_beside_the_runs_is_passed_over(three_seeds, tmp_path):
    """The folders beside a run are scanned for baselines: reading a FIFO found there (named
    eval.json) blocked the report for ever."""
    import os
    import threading

    (tmp_path / "pipe").mkdir()
    fifo = tmp_path / "pipe" / "eval.json"
    os.mkfifo(fifo)
    done: list[dict] = []
    thread = threading.Thread(
        target=lambda: done.append(write_report(three_seeds, tmp_path / "report")), daemon=True
    )
    thread.start()
    thread.join(timeout=60)
    if thread.is_alive():  # blocked opening the FIFO: let it go, then fail
        os.close(os.open(fifo, os.O_WRONLY))
        thread.join(timeout=60)
    fifo.unlink()
    assert done and done[0]["columns"]["zero baseline"]["kind"] == "baseline"
    assert not thread.is_alive()


def test_an_unreadable_file_beside_the_evaluations_is_left_out_with_a_warning(
    three_seeds, tmp_path, capsys
):
    # issue #55, fault 6: X/junk/eval.json, found while looking for baselines beside X/seed1,
    # stopped the report it was never given
    junk = tmp_path / "junk"
    junk.mkdir()
    (junk / "eval.json").write_bytes(b"\x89PNG not JSON")
    (tmp_path / "deep").mkdir()
    (tmp_path / "deep" / "eval.json").write_text("[" * 100_000 + "]" * 100_000)
    capsys.readouterr()
    assert main(["report", str(three_seeds[0]), "--out", str(tmp_path / "r")]) == 0
    out, err = capsys.readouterr()
    warnings = err.strip().splitlines()
    assert len(warnings) == 2 and all(w.startswith("devlearn: warning: left out ") for w in warnings)
    assert f"cannot read {junk / 'eval.json'}: it is not text" in err
    assert f"cannot read {tmp_path / 'deep' / 'eval.json'}: its JSON is nested too deeply" in err
    assert "zero baseline" in out and "skipped an unreadable evaluation found beside" in out
    # given, the same file is refused: one line, nothing written
    assert main(["report", str(junk), "--out", str(tmp_path / "r2")]) == 2
    assert capsys.readouterr().err.startswith(f"devlearn: error: cannot read {junk / 'eval.json'}")
    assert main(["report", str(tmp_path / "deep"), "--out", str(tmp_path / "r2")]) == 2
    assert "its JSON is nested too deeply" in capsys.readouterr().err
    assert not (tmp_path / "r2").exists()


def test_cli_report_prints_the_first_rows_unless_full(tmp_path, capsys):
    """An evaluation with hundreds of figures (the coded touches) prints its headline and the
    first rows, then says where the rest are; report.md and ``--full`` keep every row."""
    many = {f"extra_{i:03d}": float(i) for i in range(40)}
    paths = [fake_eval(tmp_path / f"s{s}" / "eval", 0.5 + s / 10, s, **many) for s in (1, 2)]
    out_dir = tmp_path / "r"
    assert main(["report", *map(str, paths), "--out", str(out_dir)]) == 0
    short = capsys.readouterr().out
    rows = [line for line in short.splitlines() if line.startswith("| `")]
    md_rows = [r for r in (out_dir / "report.md").read_text().splitlines() if r.startswith("| `")]
    assert len(md_rows) > 40 and len(rows) == 12
    assert rows == md_rows[:12]  # the headline leads, in report.md's order
    assert f"({len(md_rows) - 12} more metrics in {out_dir / 'report.md'}" in short
    assert "Columns:" in short  # what follows the table is still printed
    assert main(["report", *map(str, paths), "--out", str(tmp_path / "r2"), "--full"]) == 0
    full = capsys.readouterr().out
    assert [line for line in full.splitlines() if line.startswith("| `")] == md_rows
    assert "more metrics" not in full


def test_a_protocol_naming_a_criterion_leads_with_the_behaviours_headline(tmp_path, capsys):
    """Hand regard's protocol names its criterion (``detector``), not a metric: the report led
    with the first metric it met (one eye-hand pair) instead of the headline, the average over
    the four pairs. The behaviour's headline metric leads the table and the first panel."""
    protocol = {"episodes": 100, "seed": 0, "settle_steps": 0, "headline": "detector"}
    figures = {"visibility": {"left_eye_left_hand": 0.9}, "protocol": protocol}
    paths = [
        fake_eval(tmp_path / f"s{s}" / "eval", 0.5, s, behavior="hand_regard", **figures,
                  average=0.4 + s / 100, episode_average_mean=0.4 + s / 100)
        for s in (1, 2)
    ]
    unled = write_report(paths, tmp_path / "r1")
    assert unled["metrics"][0] != "episode_average_mean"  # today's fault, without the behaviour
    led = write_report(paths, tmp_path / "r2", behavior_headline=lambda name: "average")
    assert led["metrics"][0] == "episode_average_mean"
    assert main(["report", *map(str, paths), "--out", str(tmp_path / "r3")]) == 0
    rows = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| `")]
    assert rows[0].startswith("| `episode_average_mean` |")  # the CLI asks the behaviour
