"""``devlearn curve RUN_DIR [RUN_DIR ...]``: plot learning curves from runs' metrics.jsonl."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from devlearn.errors import UsageError


def add_parser(subparsers) -> list[str]:
    """Register the ``curve`` sub-command."""
    p = subparsers.add_parser("curve", help="plot metrics of a run against environment steps")
    p.add_argument(
        "run_dirs",
        type=Path,
        nargs="+",
        metavar="RUN_DIR",
        help="run folders holding metrics.jsonl (several: one line each, e.g. an ablation)",
    )
    p.add_argument(
        "--metric",
        action="append",
        default=None,
        help="metrics.jsonl key to plot (repeatable; default: every metrics/* key)",
    )
    p.add_argument("--smooth", type=int, default=10, help="moving-average window (iterations)")
    p.add_argument("--out", type=Path, help="PNG path (default: FIRST_RUN_DIR/learning_curve.png)")
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


def run(args: argparse.Namespace, registry) -> int:
    """Plot the chosen metrics (moving average) against steps and write a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    runs = [(run_dir, read_metrics(run_dir)) for run_dir in args.run_dirs]
    every = {k for _, rows in runs for r in rows for k in r}
    keys = args.metric or sorted(k for k in every if k.startswith("metrics/"))
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
            window = min(args.smooth, len(values))
            smooth = np.convolve(values, np.ones(window) / window, mode="valid")
            if len(runs) == 1:
                ax.plot(steps, values, color="0.8", lw=0.8)
            ax.plot(steps[window - 1 :], smooth, lw=1.6, label=run_dir.name)
        ax.set_ylabel(key.split("/")[-1])
        ax.grid(alpha=0.3)
    if len(runs) > 1:
        axes[0, 0].legend(fontsize=8)
    axes[-1, 0].set_xlabel("environment steps")
    title = args.run_dirs[0].name if len(runs) == 1 else f"{len(runs)} runs"
    fig.suptitle(f"{title}: mean over episodes ending in each iteration")
    fig.tight_layout()
    out = args.out or args.run_dirs[0] / "learning_curve.png"
    fig.savefig(out, dpi=110)
    print(out)
    return 0
