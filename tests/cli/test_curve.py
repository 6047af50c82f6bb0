"""``devlearn curve`` plots metrics.jsonl and refuses bad input with one line."""

from __future__ import annotations

import argparse
import json

import pytest

from devlearn.cli import curve
from devlearn.errors import UsageError


def _args(run_dir, **kw):
    base = {"run_dirs": [run_dir], "metric": None, "smooth": 3, "out": None}
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
    with pytest.raises(UsageError, match="metrics.jsonl does not exist"):
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
    with pytest.raises(UsageError, match="c/metrics.jsonl does not exist"):
        curve.run(args, None)
