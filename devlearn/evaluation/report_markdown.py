"""The Markdown table of ``devlearn report`` (report.md)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from devlearn.api.stats import CONFIDENCE


def shown(path: Path) -> str:
    """``path`` relative to the working directory when inside it (reports get committed)."""
    try:
        return str(path.relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)


def cell(stat: dict[str, Any]) -> str:
    """``mean [low, high]``, the mean alone without an interval, ``-`` without a value."""
    if stat["mean"] is None:
        return "-"
    if stat["ci_low"] is None:
        return f"{stat['mean']:.3g}"
    return f"{stat['mean']:.3g} [{stat['ci_low']:.3g}, {stat['ci_high']:.3g}]"


def column_title(name: str, info: dict[str, Any]) -> str:
    """A column's heading: its name and, for our runs and baselines, how many there are."""
    return name if info["kind"] == "paper" else f"{name} (n={len(info['seeds'])})"


def _runs(info: dict[str, Any]) -> str:
    """``seeds [1, 2, 3]`` for trained runs; baselines have no training seed: their count."""
    seeds = [s for s in info["seeds"] if s is not None]
    if not seeds:
        count = len(info["seeds"])
        return f"{count} evaluation{'s' if count != 1 else ''} of an untrained policy (no seed)"
    return f"seeds {seeds}"


def markdown(result: dict[str, Any], evaluations: list[tuple[Path, dict]]) -> str:
    cols = list(result["columns"])
    protocol = evaluations[0][1]["protocol"]
    lines = [
        f"# {result['behavior']}: evaluation report",
        "",
        f"Mean and {CONFIDENCE:.0%} t-interval over seeds (baselines: over their "
        f"evaluations). Protocol: {protocol.get('episodes')} episodes, eval seed "
        f"{protocol.get('seed')}, settle {protocol.get('settle_steps')} steps, headline "
        f"`{protocol.get('headline')}`.",
        "",
    ]
    header = ["metric"] + [column_title(c, result["columns"][c]) for c in cols]
    lines += ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for metric, row in result["table"].items():
        lines.append("| " + " | ".join([f"`{metric}`"] + [cell(row[c]) for c in cols]) + " |")
    lines += ["", "Columns:"]
    for c, info in result["columns"].items():
        if info["kind"] == "paper":
            lines.append(f"- **{c}**: the paper's published figures (- where it gives none)")
        else:
            lines.append(f"- **{c}**: {_runs(info)} from {', '.join(info['paths'])}")
    if result["notes"]:
        lines += ["", "Notes:"] + [f"- {n}" for n in result["notes"]]
    return "\n".join(lines) + "\n"
