"""Issue #38's proof table: every seed's evaluation beside the zero and random baselines under
the same protocol, per start (the default protocol and the rest pose), mean and 95% t-interval
over seeds. From the repository root:
    python results/plugins/table.py results/plugins/hand_to_mouth
reads OUT/runs/seed=N/{eval,rest}/eval.json and OUT/baseline_{zero,random}[_rest]/eval.json
(results/plugins/proof.sh's layout) and prints a markdown table."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from devlearn.api.stats import mean_ci

SKIP = {"episodes", "steps", "checkpoint_env_steps", "training_seed"}
"""Summary numbers that describe the protocol, not the behaviour."""


def measures(summary: dict) -> dict[str, float]:
    """The evaluator's numeric figures of one eval.json."""
    return {
        k: float(v)
        for k, v in summary.items()
        if k not in SKIP and isinstance(v, (int, float)) and not isinstance(v, bool)
    }


def interval(values: list[float]) -> str:
    """``mean [low, high]``: the 95% t-interval over seeds (devlearn's ``mean_ci``, as
    ``devlearn report`` computes it); the mean alone for one value."""
    stats = mean_ci(values)
    if stats["ci_low"] is None:
        return f"{stats['mean']:.3f}"
    return f"{stats['mean']:.3f} [{stats['ci_low']:.3f}, {stats['ci_high']:.3f}]"


def main(out: Path) -> None:
    seeds = sorted(out.glob("runs/seed=*"), key=lambda p: int(p.name.split("=")[1]))
    protocols = (
        ("eval", "", "default protocol, mean action"),
        ("sample", "", "default protocol, actions sampled from the policy (--action sample)"),
        ("rest", "_rest", "rest pose (--start rest), mean action"),
    )
    for folder, suffix, label in protocols:
        runs = [json.loads((s / folder / "eval.json").read_text()) for s in seeds]
        base = {
            p: json.loads((out / f"baseline_{p}{suffix}" / "eval.json").read_text())
            for p in ("zero", "random")
        }
        names = list(measures(runs[0]))
        starts = {r["start"] for r in runs} | {b["start"] for b in base.values()}
        print(f"\n**{label}**: episodes start from {', '.join(sorted(starts))}; "
              f"{runs[0]['protocol']['episodes']} episodes, eval seed "
              f"{runs[0]['protocol']['seed']}\n")
        print("| policy | " + " | ".join(names) + " |")
        print("|---" * (len(names) + 1) + "|")
        per_seed = {n: [measures(r)[n] for r in runs] for n in names}
        print(f"| **trained, {len(runs)} seeds** (mean [95% interval]) | "
              + " | ".join(f"**{interval(per_seed[n])}**" for n in names) + " |")
        print("| per seed | " + " | ".join(
            ", ".join(f"{v:.3f}" for v in per_seed[n]) for n in names) + " |")
        for policy, summary in base.items():
            print(f"| {policy} actions | "
                  + " | ".join(f"{measures(summary)[n]:.3f}" for n in names) + " |")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
