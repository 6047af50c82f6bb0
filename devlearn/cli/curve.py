"""``devlearn curve DIR [DIR ...]``: plot learning curves.

Run folders (``metrics.jsonl``, from ``devlearn run``) give one line each: training metrics per
iteration. Evaluation folders (``eval.json``, from ``devlearn eval --out``) of checkpoints of one
run give together one line: each evaluation is a point at its checkpoint's environment steps;
``--vs`` adds another line (say, the evaluations of a second run, to compare the two).
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

from devlearn.errors import UsageError


def add_parser(subparsers) -> list[str]:
    """Register the ``curve`` sub-command."""
    p = subparsers.add_parser("curve", help="plot metrics of a run against environment steps")
    p.add_argument(
        "run_dirs",
        type=Path,
        nargs="+",
        metavar="DIR",
        help="run folders holding metrics.jsonl (several: one line each, e.g. an ablation), "
        "or evaluation folders holding eval.json (together: one point per checkpoint)",
    )
    p.add_argument(
        "--metric",
        action="append",
        default=None,
        help="metrics.jsonl or eval.json key to plot (repeatable; default: every metrics/* "
        "key of runs, every numeric key of evaluations)",
    )
    p.add_argument(
        "--vs",
        action="append",
        nargs="+",
        type=Path,
        default=None,
        metavar="DIR",
        help="another line to compare: evaluation folders of another run (repeatable)",
    )
    p.add_argument("--smooth", type=int, default=10, help="moving-average window (iterations)")
    p.add_argument("--out", type=Path, help="PNG path (default: FIRST_DIR/learning_curve.png)")
    return ["curve"]


def read_metrics(run_dir: Path) -> list[dict]:
    """Return the rows of ``run_dir/metrics.jsonl`` (one dict per iteration)."""
    path = run_dir / "metrics.jsonl"
    if not path.exists():
        raise UsageError(f"{path} does not exist; pass a folder made by `devlearn run`")
    rows = []
    for line in path.read_text().splitlines():
        try:
            rows.append(json.loads(line))
        except ValueError:
            continue  # a line cut short by a kill
    if not rows:
        raise UsageError(f"{path} holds no complete rows yet")
    return rows


def read_evaluations(eval_dirs: list[Path]) -> list[dict]:
    """Each folder's ``eval.json`` as a ``step``-keyed row (``checkpoint_env_steps``), by step."""
    rows = []
    for eval_dir in eval_dirs:
        path = eval_dir / "eval.json"
        if not path.exists():
            raise UsageError(
                f"{eval_dir} holds neither metrics.jsonl (a run) nor eval.json (an evaluation)"
            )
        summary = json.loads(path.read_text())
        if "checkpoint_env_steps" not in summary:
            raise UsageError(
                f"{path} has no checkpoint_env_steps (older evaluations lack it): "
                "evaluate the checkpoint again"
            )
        numbers = {k: v for k, v in summary.items() if isinstance(v, (int, float))}
        rows.append({**numbers, "step": summary["checkpoint_env_steps"]})
    return sorted(rows, key=lambda row: row["step"])


def _load(groups: list[list[Path]]) -> tuple[list[tuple[Path, list[dict]]], bool]:
    """(label, rows) per line, and whether these are evaluations; one kind of folder only.

    Runs: one line per folder. Evaluations: one line per group (the positional folders, then
    each ``--vs``), labelled by the folders' common parent.
    """
    dirs = [d for group in groups for d in group]
    evaluations = [d for d in dirs if not (d / "metrics.jsonl").exists()]
    if not evaluations:
        return [(run_dir, read_metrics(run_dir)) for run_dir in dirs], False
    if len(evaluations) < len(dirs):
        raise UsageError("give either run folders or evaluation folders, not both")
    if len(groups) == 1:
        return [(Path("evaluation"), read_evaluations(dirs))], True
    common = [Path(os.path.commonpath([d.resolve() for d in g])) for g in groups]
    return [(Path(os.path.relpath(c)), read_evaluations(g)) for c, g in zip(common, groups)], True


def run(args: argparse.Namespace, registry) -> int:
    """Plot the chosen metrics (moving average) against steps and write a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    runs, evaluations = _load([list(args.run_dirs), *(args.vs or [])])
    every = {k for _, rows in runs for r in rows for k in r}
    default = (k for k in every if k not in ("step", "checkpoint_env_steps", "episodes"))
    if not evaluations:
        default = (k for k in every if k.startswith("metrics/"))
    keys = args.metric or sorted(default) or ["mean_step_reward"]  # before any episode ended
    unknown = [k for k in keys if k not in every]
    if unknown or not keys:
        raise UsageError(f"no such metric(s) {unknown}; valid: {', '.join(sorted(every))}")
    if args.smooth < 1:
        raise UsageError("--smooth must be at least 1")
    fig, axes = plt.subplots(len(keys), 1, figsize=(7, 2.4 * len(keys)), squeeze=False)
    for ax, key in zip(axes[:, 0], keys):
        for run_dir, rows in runs:
            points = [(r["step"], r[key]) for r in rows if r.get(key) is not None]
            if not points:
                continue
            steps, values = (np.array(v, dtype=float) for v in zip(*points))
            if evaluations:
                ax.plot(steps, values, marker="o", lw=1.6, label=str(run_dir))
                continue
            window = min(args.smooth, len(values))
            smooth = np.convolve(values, np.ones(window) / window, mode="valid")
            if len(runs) == 1:
                ax.plot(steps, values, color="0.8", lw=0.8)
            ax.plot(steps[window - 1 :], smooth, lw=1.6, label=run_dir.name)
        ax.set_ylabel(key.split("/")[-1])
        ax.grid(alpha=0.3)
    if len(runs) > 1:
        axes[0, 0].legend(fontsize=8)
    title = args.run_dirs[0].name if len(runs) == 1 else f"{len(runs)} runs"
    if evaluations:
        axes[-1, 0].set_xlabel("environment steps of the checkpoint")
        count = sum(len(rows) for _, rows in runs)
        fig.suptitle(f"evaluations of {count} checkpoints")
    else:
        axes[-1, 0].set_xlabel("environment steps")
        fig.suptitle(f"{title}: mean over episodes ending in each iteration")
    fig.tight_layout()
    out = args.out or args.run_dirs[0] / "learning_curve.png"
    fig.savefig(out, dpi=110)
    print(out)
    return 0
