"""Issue #45's comparison table from what ``experiment.sh`` wrote:
``python results/learners/table.py OUT``.

One row per learner (devlearn's PPO, SB3 PPO, SB3 SAC) and per baseline: the per-episode
self-touch score (parts touched per episode by both hands / 68, the mean over the 100 evaluation
episodes; the headline of ``results/self_touch/``) as the mean and 95% t-interval over seeds, the
union score (BabyBench's) likewise, the physics steps each run trained and its seconds of
learning (devlearn: collect + update summed over metrics.jsonl; SB3: ``learn_s``), then each
seed's figures.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

from devlearn.api.stats import mean_ci

LEARNERS = ("devlearn_ppo", "sb3_ppo", "sb3_sac")


def _run_figures(run: Path) -> dict[str, float]:
    """Steps trained and seconds of learning of one run folder."""
    train = run / "train.json"
    if train.exists():  # SB3 (examples/sb3/train.py); devlearn runs as publish.sh writes them
        data = json.loads(train.read_text())
        return {"steps": data["env_steps"], "seconds": data["learn_s"]}
    rows = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
    seconds = sum(r["collect_s"] + r["update_s"] for r in rows)
    return {"steps": rows[-1]["step"], "seconds": seconds}


def _interval(values: list[float], digits: int = 3) -> str:
    stats = mean_ci(values)
    if stats["ci_low"] is None:
        return f"{stats['mean']:.{digits}f} (n={len(values)})"
    return (
        f"{stats['mean']:.{digits}f} [{stats['ci_low']:.{digits}f}, {stats['ci_high']:.{digits}f}]"
    )


def main(out: Path) -> None:
    print("| policy | seeds | per-episode score | union score | physics steps | s of learning |")
    print("|---|---|---|---|---|---|")
    per_seed: list[str] = []
    for learner in LEARNERS:
        runs = sorted((out / learner).glob("seed=*"))
        evals: list[dict[str, Any]] = []
        figures: list[dict[str, float]] = []
        for run in runs:
            path = run / "eval" / "eval.json"
            if not path.exists():
                continue
            evals.append(json.loads(path.read_text()))
            figures.append(_run_figures(run))
            e, f = evals[-1], figures[-1]
            per_seed.append(
                f"| {learner} | {run.name} | {e['episode_score_mean']:.3f} "
                f"[{e['episode_score_ci_low']:.3f}, {e['episode_score_ci_high']:.3f}] | "
                f"{e['score']:.3f} | {f['steps']:,} | {f['seconds']:,.0f} |"
            )
        if not evals:
            continue
        print(
            f"| {learner} | {len(evals)} | "
            f"{_interval([e['episode_score_mean'] for e in evals])} | "
            f"{_interval([e['score'] for e in evals])} | "
            f"{_interval([f['steps'] for f in figures], 0)} | "
            f"{_interval([f['seconds'] for f in figures], 0)} |"
        )
    for name in ("zero", "random"):
        path = out / f"baseline_{name}" / "eval.json"
        if path.exists():
            e = json.loads(path.read_text())
            print(
                f"| {name} actions | - | {e['episode_score_mean']:.3f} | {e['score']:.3f} | - | - |"
            )
    print("\nPer seed (per-episode score with its 95% t-interval over the 100 episodes):\n")
    print("| learner | seed | per-episode score | union score | physics steps | s of learning |")
    print("|---|---|---|---|---|---|")
    print("\n".join(per_seed))


if __name__ == "__main__":
    if len(sys.argv) != 2:
        raise SystemExit(__doc__)
    main(Path(sys.argv[1]))
