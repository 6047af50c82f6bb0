"""Issue #28's tables from committed files: ``python results/learner/table.py [FOLDER ...]``.

Each FOLDER holds one arm per sub-folder (``ARM/seed=N/`` with the run's ``eval.json`` and
``metrics.jsonl``) and baselines' evaluations in ``baseline_*/eval.json``.
Per arm: the evaluation's per-episode score (the headline: mean and 95% t-interval over seeds,
then each seed's own value), the union score, and the learner's health over the run's last 10
iterations (training per-episode score of the stochastic policy, surrogate loss, explained
variance, spread, share of saturated means) and over its first 1M steps (surrogate).
"""

from __future__ import annotations

import json
import statistics
import sys
from pathlib import Path

from devlearn.api.stats import mean_ci


def _ci(values: list[float], digits: int = 3) -> str:
    stats = mean_ci(values)
    if stats["ci_low"] is None:
        return f"{stats['mean']:.{digits}f}"
    return (
        f"{stats['mean']:.{digits}f} [{stats['ci_low']:.{digits}f}, {stats['ci_high']:.{digits}f}]"
    )


def _last(rows: list[dict], key: str, n: int = 10) -> float:
    values = [r[key] for r in rows[-n:] if r.get(key) is not None]
    return statistics.mean(values) if values else float("nan")


def arm_row(name: str, seeds: list[Path]) -> str:
    """One arm's row; runs without a metrics.jsonl (published evaluations of older runs) show
    '-' for the learner's figures."""
    evals = [json.loads((s / "eval.json").read_text()) for s in seeds]
    per_episode = [e["episode_score_mean"] for e in evals]
    cells = [
        name,
        str(len(seeds)),
        _ci(per_episode),
        ", ".join(f"{v:.3f}" for v in per_episode),
        _ci([e["score"] for e in evals], 2),
    ]
    if all((s / "metrics.jsonl").exists() for s in seeds):
        rows = [
            [json.loads(x) for x in (s / "metrics.jsonl").read_text().splitlines()] for s in seeds
        ]
        early = [
            statistics.mean(r["loss/surrogate"] for r in run if r["step"] <= 1_000_000)
            for run in rows
        ]
        cells += [
            _ci([_last(run, "metrics/score") for run in rows]),
            _ci(early, 4),
            _ci([_last(run, "health/explained_variance") for run in rows], 2),
            _ci([_last(run, "health/std_mean") for run in rows], 2),
            _ci([_last(run, "health/saturated") for run in rows], 2),
        ]
    else:
        cells += ["-"] * 5
    return "| " + " | ".join(cells) + " |"


HEADER = (
    "| arm | seeds | eval per-episode score | per seed | eval union score "
    "| training per-episode score (last 10 it.) | surrogate (first 1M steps) "
    "| explained variance | spread | saturated means |\n"
    "|---|---|---|---|---|---|---|---|---|---|"
)


def table(folder: Path) -> str:
    lines = [HEADER]
    for arm in sorted(p for p in folder.iterdir() if p.is_dir() and "baseline" not in p.name):
        seeds = sorted(s for s in arm.glob("seed=*") if (s / "eval.json").exists())
        if seeds:
            lines.append(arm_row(arm.name, seeds))
    for path in sorted(folder.glob("baseline_*/eval.json")):
        e = json.loads(path.read_text())
        repeat = e["protocol"].get("action_repeat", 1)  # evaluations before issue #28: 1
        policy = e["protocol"]["policy"]
        lines.append(
            f"| {policy} actions (held {repeat} physics steps), {e['protocol']['episodes']} "
            f"episodes | - "
            f"| {e['episode_score_mean']:.3f} | - | {e['score']:.2f} | - | - | - | - | - |"
        )
    return "\n".join(lines)


if __name__ == "__main__":
    for arg in sys.argv[1:] or ["results/learner/pilot"]:
        print(f"### {arg}\n\n{table(Path(arg))}\n")
