"""``devlearn curve`` plots metrics.jsonl and refuses bad input with one line."""

from __future__ import annotations

import argparse
import json

import pytest

from devlearn.cli import curve
from devlearn.errors import UsageError


def _args(run_dir, **kw):
    base = {"run_dir": run_dir, "metric": None, "smooth": 3, "out": None}
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
