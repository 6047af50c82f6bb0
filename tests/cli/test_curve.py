"""``devlearn curve`` plots metrics.jsonl and refuses bad input with one line."""

from __future__ import annotations

import argparse
import json

import pytest

from devlearn.api.errors import UsageError
from devlearn.cli import curve


def _args(run_dir, **kw):
    base = {"run_dirs": [run_dir], "metric": None, "smooth": 3, "out": None, "vs": None,
            "health": False}
    return argparse.Namespace(**{**base, **kw})


def test_curve_writes_png(tmp_path):
    rows = [{"step": 100 * i, "metrics/score": i / 10, "mean_reward": i} for i in range(8)]
    rows[2]["metrics/score"] = None  # an iteration where no episode ended
    text = "\n".join(json.dumps(r) for r in rows) + '\n{"step": 9'  # last line cut by a kill
    (tmp_path / "metrics.jsonl").write_text(text)
    assert curve.run(_args(tmp_path), None) == 0
    png = (tmp_path / "learning_curve.png").read_bytes()
    assert png[:4] == b"\x89PNG" and len(png) > 5000


def test_curve_errors(tmp_path):
    with pytest.raises(UsageError, match="holds neither metrics.jsonl .* nor eval.json"):
        curve.run(_args(tmp_path), None)
    (tmp_path / "metrics.jsonl").write_text('{"step": 1, "metrics/score": 0.1}\n')
    with pytest.raises(UsageError, match="valid: metrics/score, step"):
        curve.run(_args(tmp_path, metric=["metrics/nope"]), None)


def test_curve_compares_runs(tmp_path):
    for name, slope in (("a", 1.0), ("b", 2.0)):
        (tmp_path / name).mkdir()
        rows = [{"step": 100 * i, "metrics/score": slope * i} for i in range(6)]
        (tmp_path / name / "metrics.jsonl").write_text("\n".join(json.dumps(r) for r in rows))
    out = tmp_path / "both.png"
    args = _args(tmp_path / "a", out=out, metric=["metrics/score"])
    args.run_dirs.append(tmp_path / "b")
    assert curve.run(args, None) == 0
    assert out.read_bytes()[:4] == b"\x89PNG"
    (tmp_path / "c").mkdir()
    args.run_dirs.append(tmp_path / "c")
    with pytest.raises(UsageError, match="either run folders or evaluation folders, not both"):
        curve.run(args, None)


def test_curve_of_evaluations_orders_checkpoints_by_steps(tmp_path):
    dirs = []
    for steps, score in ((2000, 0.5), (1000, 0.25), (3000, 0.75)):
        eval_dir = tmp_path / f"eval_{steps}"
        eval_dir.mkdir()
        summary = {"episodes": 4, "score": score, "coverage": [1, 2], "checkpoint_env_steps": steps}
        (eval_dir / "eval.json").write_text(json.dumps(summary))
        dirs.append(eval_dir)
    rows = curve.read_evaluations(dirs)
    assert [(r["step"], r["score"]) for r in rows] == [(1000, 0.25), (2000, 0.5), (3000, 0.75)]
    assert "coverage" not in rows[0]  # only numbers are plotted
    out = tmp_path / "evals.png"
    args = _args(dirs[0], out=out)
    args.run_dirs = dirs
    assert curve.run(args, None) == 0
    assert out.read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(UsageError, match="valid: checkpoint_env_steps, episodes, score, step"):
        curve.run(_args(dirs[0], metric=["nope"]), None)
    (dirs[0] / "eval.json").write_text(json.dumps({"score": 0.1}))
    with pytest.raises(UsageError, match="no checkpoint_env_steps .* evaluate the checkpoint"):
        curve.run(_args(dirs[0]), None)


def test_curve_compares_the_evaluations_of_two_runs(tmp_path, monkeypatch):
    def evals(run, scores):
        dirs = []
        for steps, score in scores:
            eval_dir = tmp_path / run / "evals" / f"at_{steps}"
            eval_dir.mkdir(parents=True)
            summary = {"score": score, "checkpoint_env_steps": steps}
            (eval_dir / "eval.json").write_text(json.dumps(summary))
            dirs.append(eval_dir)
        return dirs

    first = evals("a", ((1000, 0.5), (2000, 0.6)))
    second = evals("b", ((2000, 0.9), (1000, 0.7)))
    monkeypatch.chdir(tmp_path)
    lines, evaluations = curve._load([first, second])
    assert evaluations
    assert [str(label) for label, _ in lines] == ["a/evals", "b/evals"]
    assert [r["score"] for r in lines[1][1]] == [0.7, 0.9]  # each line by steps
    out = tmp_path / "vs.png"
    args = _args(first[0], out=out, metric=["score"], vs=[second])
    args.run_dirs = first
    assert curve.run(args, None) == 0
    assert out.read_bytes()[:4] == b"\x89PNG"


def test_curve_of_evaluations_draws_headlines_keeps_starts_apart_and_saves_beside(
    tmp_path, monkeypatch
):
    from matplotlib.figure import Figure

    run = tmp_path / "run"
    dirs = []
    for steps in (1000, 2000):
        for start, score in (("stage", 0.2 * steps / 1000), ("rest", 0.9)):
            eval_dir = run / f"eval_{steps}_{start}"
            eval_dir.mkdir(parents=True)
            summary = {
                "episodes": 100,
                "score": score,
                "coverage_total": 30,
                "settle_steps": 10,
                "episode_score_mean": score / 2,
                "episode_score_std": 0.1,
                "episode_score_ci_low": score / 2 - 0.05,
                "episode_score_ci_high": score / 2 + 0.05,
                "training_seed": 1,
                "checkpoint_env_steps": steps,
                "protocol": {"headline": "score", "start": start, "stage": {"random_pose": True}},
            }
            (eval_dir / "eval.json").write_text(json.dumps(summary))
            dirs.append(eval_dir)
    rows = curve.read_evaluations(dirs)
    assert curve.default_eval_metrics(rows) == ["score", "episode_score_mean"]
    lines = curve._by_start([(run, rows)])
    assert [label for label, _ in lines] == [f"{run}, random starts", f"{run}, rest start"]
    assert [r["score"] for r in lines[0][1]] == [0.2, 0.4] and [
        r["score"] for r in lines[1][1]
    ] == [0.9, 0.9]
    drawn = []
    save = Figure.savefig
    monkeypatch.setattr(
        Figure, "savefig", lambda fig, *a, **k: (drawn.append(fig), save(fig, *a, **k))
    )
    args = _args(dirs[0])
    args.run_dirs = dirs
    assert curve.run(args, None) == 0
    assert (run / "eval_curve.png").exists()  # beside the evaluations, not inside one
    assert not any(p.name.endswith(".png") for d in dirs for p in d.iterdir())
    (fig,) = drawn
    assert [ax.get_ylabel() for ax in fig.axes] == ["score", "episode_score_mean"]
    assert all(len(ax.get_lines()) == 2 for ax in fig.axes)  # one line per start
    assert "evaluations of 2 checkpoints (random starts / rest start)" in fig._suptitle.get_text()


def test_the_legend_of_many_runs_does_not_cover_the_curves(tmp_path, monkeypatch):
    import matplotlib.pyplot as plt

    figures = []
    monkeypatch.setattr(plt.Figure, "savefig", lambda fig, *a, **k: figures.append(fig))
    names = [f"seed={i}" for i in range(11)]
    for i, name in enumerate(names):
        (tmp_path / name).mkdir()
        rows = [{"step": 100 * s, "metrics/score": i * s} for s in range(6)]
        (tmp_path / name / "metrics.jsonl").write_text("\n".join(json.dumps(r) for r in rows))
    args = _args(tmp_path / names[0], out=tmp_path / "all.png", metric=["metrics/score"])
    args.run_dirs += [tmp_path / n for n in names[1:]]
    assert curve.run(args, None) == 0
    fig = figures[0]
    fig.canvas.draw()
    ax = fig.axes[0]
    legend = ax.get_legend().get_window_extent()
    assert [t.get_text() for t in ax.get_legend().get_texts()] == names
    assert not legend.overlaps(ax.get_window_extent())
    assert len({tuple(line.get_color()) for line in ax.get_lines()}) == len(names)  # no repeats


def test_a_run_curve_leads_with_the_headline_and_reward_and_draws_no_counters(
    tmp_path, monkeypatch
):
    import matplotlib.pyplot as plt

    from devlearn.plugins import PluginRegistry

    figures = []
    monkeypatch.setattr(plt.Figure, "savefig", lambda fig, *a, **k: figures.append(fig))
    row = {"step": 0, "mean_reward": 1.0, "metrics/balance": 2.0, "metrics/coverage_left": 0.1,
           "metrics/score": 0.3, "metrics/training_score_episodes": 40,
           "health/std_mean": 0.5, "health/saturated": 0.1, "learning_rate": 3e-4}  # fmt: skip
    rows = [{**row, "step": 100 * i} for i in range(6)]
    (tmp_path / "metrics.jsonl").write_text("\n".join(json.dumps(r) for r in rows))
    (tmp_path / "config.json").write_text(json.dumps({"behavior_name": "self_touch"}))
    registry = PluginRegistry()
    assert curve.run(_args(tmp_path), registry) == 0
    labels = [ax.get_ylabel() for ax in figures[0].axes]
    assert labels == ["score", "mean_reward", "balance", "coverage_left"]  # headline first
    fig = figures[0]
    fig.canvas.draw()
    title = fig.get_suptitle() and fig._suptitle.get_window_extent()
    assert title.y0 >= fig.axes[0].get_tightbbox().y1  # the title above the first panel
    assert curve.run(_args(tmp_path, health=True), registry) == 0
    labels = [ax.get_ylabel() for ax in figures[1].axes]
    assert labels[4:] == ["saturated", "std_mean", "learning_rate"]


def test_lines_that_are_no_metrics_row_are_skipped_with_a_warning(tmp_path, capsys):
    # issue #55, fault 9: a [1,2,3] line, a "step": 1e308 and numbers given as text were
    # tracebacks (AttributeError, ValueError); a binary file a UnicodeDecodeError
    good = [{"step": 100 * i, "mean_reward": float(i)} for i in range(4)]
    lines = [json.dumps(r) for r in good]
    lines[1:1] = ["[1, 2, 3]", '{"step": 1e308, "mean_reward": 1.0}', '"text"', '{"step": true}']
    lines.append('{"step": 500, "mean_reward": "high", "metrics/x": [1]}')  # no number: none
    (tmp_path / "metrics.jsonl").write_text("\n".join(lines) + "\n")
    assert curve.run(_args(tmp_path), None) == 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "devlearn: warning: " in err
    assert "skipped 4 line(s) (2, 3, 4, 5): not a metrics row" in err
    rows = curve.read_metrics(tmp_path)
    assert [r["step"] for r in rows] == [0, 100, 200, 300, 500] and "mean_reward" not in rows[-1]
    (tmp_path / "metrics.jsonl").write_bytes(bytes(range(256)) * 40)
    with pytest.raises(UsageError, match="metrics.jsonl holds no complete rows yet"):
        curve.run(_args(tmp_path), None)


def test_json_nested_too_deeply_is_one_line(tmp_path):
    # issue #55, fault 8: RecursionError tracebacks
    deep = '{"a":' * 100_000 + "1" + "}" * 100_000
    eval_dir = tmp_path / "eval"
    eval_dir.mkdir()
    (eval_dir / "eval.json").write_text(deep)
    with pytest.raises(UsageError, match="eval.json: its JSON is nested too deeply"):
        curve.run(_args(eval_dir), None)
    run_dir = tmp_path / "run"
    run_dir.mkdir()
    (run_dir / "metrics.jsonl").write_text(deep + "\n" + json.dumps({"step": 1, "a": 2.0}) + "\n")
    (run_dir / "config.json").write_text(deep)
    assert [r["step"] for r in curve.read_metrics(run_dir)] == [1]
    assert curve.run_headline(run_dir, None) is None


def test_out_names_the_file_it_writes(tmp_path, capsys):
    # issue #55, fault 14: `--out plot` wrote plot.png and printed plot
    (tmp_path / "metrics.jsonl").write_text('{"step": 1, "mean_reward": 1.0}\n')
    assert curve.run(_args(tmp_path, out=str(tmp_path / "plot")), None) == 0
    assert capsys.readouterr().out.strip() == str(tmp_path / "plot.png")
    assert (tmp_path / "plot.png").read_bytes()[:4] == b"\x89PNG"
    assert curve.run(_args(tmp_path, out=str(tmp_path / "plot.svg")), None) == 0
    assert capsys.readouterr().out.strip() == str(tmp_path / "plot.svg")
    with pytest.raises(UsageError, match=r"--out .*plot.v2: no picture format 'v2'; .*\.png"):
        curve.run(_args(tmp_path, out=str(tmp_path / "plot.v2")), None)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["metrics.jsonl", "plot.png", "plot.svg"]
