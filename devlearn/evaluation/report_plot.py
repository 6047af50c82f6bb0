"""The bar chart of ``devlearn report``: one panel per metric, error bars the 95% interval."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

MAX_PANELS = 4
"""Metrics drawn (the headline first, in the report's order)."""


def draw_report(result: dict[str, Any], path: Path) -> Path:
    """Draw ``write_report``'s table as bars (deterministic: no timestamps in the PNG).

    Args:
        result: What :func:`devlearn.evaluation.report.write_report` returns.
        path: PNG to write.
    Returns:
        ``path``.
    """
    from matplotlib.figure import Figure  # no pyplot: no global backend state

    metrics = result["metrics"][:MAX_PANELS]
    columns = list(result["columns"])
    fig = Figure(figsize=(3.2 * max(len(metrics), 1), 3.6), constrained_layout=True)
    axes = np.atleast_1d(fig.subplots(1, max(len(metrics), 1)))
    colours = [f"C{i}" for i in range(len(columns))]
    kinds = {c: info["kind"] for c, info in result["columns"].items()}
    for ax, metric in zip(axes, metrics):
        row = result["table"][metric]
        means = [row[c]["mean"] if row[c]["mean"] is not None else np.nan for c in columns]
        low = [
            m - row[c]["ci_low"] if row[c]["ci_low"] is not None else 0.0
            for m, c in zip(means, columns)
        ]
        high = [
            row[c]["ci_high"] - m if row[c]["ci_high"] is not None else 0.0
            for m, c in zip(means, columns)
        ]
        x = np.arange(len(columns))
        ax.bar(x, means, color=colours)
        # an interval only where there is one (several runs): a single run's bar has no caps
        spread = [i for i, c in enumerate(columns) if row[c]["ci_low"] is not None]
        if spread:
            ax.errorbar(
                x[spread],
                np.array(means)[spread],
                yerr=[np.array(low)[spread], np.array(high)[spread]],
                fmt="none",
                ecolor="k",
                capsize=4,
            )
        for i, c in enumerate(columns):  # the seeds themselves
            values = row[c]["values"]
            ax.plot(np.full(len(values), i), values, "k.", markersize=4)
        ticks = [c if kinds[c] == "paper" else f"{c}\n(n={row[c]['n']})" for c in columns]
        ax.set_xticks(x, ticks, fontsize=7, rotation=20)
        ax.set_title(metric, fontsize=9)
    fig.suptitle(f"{result['behavior']}: mean and 95% interval over seeds", fontsize=10)
    fig.savefig(path, dpi=110, metadata={"Software": None})
    return path
