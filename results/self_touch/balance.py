"""Issue #43 item 2: what drives the per-episode imbalance |left - right| of self-touch policies.

``python results/self_touch/balance.py EVAL_JSON [EVAL_JSON ...]`` (e.g. the five final
checkpoints of ``i30/curriculum/runs/seed=*/eval/eval.json``) prints, per evaluation, the parts
each hand touches per episode and splits the mean imbalance E|L - R| into its two sources:

- **a hand preference** of the policy: the mean signed difference mean(L - R), the same in every
  episode (a seed that learned to explore more with one hand);
- **episode-to-episode spread**: each hand's coverage varies with the start pose, and the two
  hands vary partly independently (corr(L, R)).

``without preference`` is E|d - round(mean d)|: the imbalance left if the policy's constant
hand preference were removed; ``hands independent`` is E|L - R'| with R shuffled across
episodes (the imbalance if the hands' coverages were unrelated), for scale. ``bonus paid`` is
the share of episodes whose |L - R| <= 3, the balance term's tolerance (R_balance pays then).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

TOLERANCE = 3
"""The balance term's tolerance (``behavior.rewards.balance.params.tolerance``) and issue #43's
target for the mean per-episode balance."""


def _episode_parts(doc: dict[str, Any]) -> list[dict[str, list[int]]]:
    """The per-episode touched parts per hand, wherever the eval JSON nests them."""
    stack: list[Any] = [doc]
    while stack:
        node = stack.pop()
        if isinstance(node, dict):
            if "episode_parts" in node:
                return list(node["episode_parts"])
            stack.extend(node.values())
    raise SystemExit("no 'episode_parts' in this eval.json (not a self-touch evaluation?)")


def _corr(a: np.ndarray, b: np.ndarray) -> float:
    """Pearson's correlation; NaN when a hand's coverage never varies (e.g. zero actions)."""
    if a.std() == 0 or b.std() == 0:
        return float("nan")
    return float(np.corrcoef(a, b)[0, 1])


def decompose(episodes: list[dict[str, list[int]]], seed: int = 0) -> dict[str, float]:
    """The imbalance of one evaluation and its sources (see the module docstring)."""
    left = np.array([len(e["left"]) for e in episodes], dtype=float)
    right = np.array([len(e["right"]) for e in episodes], dtype=float)
    d = left - right
    rng = np.random.default_rng(seed)
    shuffled = np.mean([np.abs(left - rng.permutation(right)).mean() for _ in range(200)])
    return {
        "episodes": float(len(d)),
        "left": float(left.mean()),
        "right": float(right.mean()),
        "balance": float(np.abs(d).mean()),
        "preference": float(d.mean()),
        "without_preference": float(np.abs(d - np.round(d.mean())).mean()),
        "corr": _corr(left, right),
        "independent": float(shuffled),
        "bonus_paid": float((np.abs(d) <= TOLERANCE).mean()),
    }


def main(paths: list[str]) -> None:
    if not paths:
        raise SystemExit(__doc__)
    cols = ["left", "right", "balance", "preference", "without_preference", "corr"]
    cols += ["independent", "bonus_paid"]
    print("| eval | " + " | ".join(c.replace("_", " ") for c in cols) + " |")
    print("|---" * (len(cols) + 1) + "|")
    rows = []
    for path in paths:
        row = decompose(_episode_parts(json.loads(Path(path).read_text())))
        rows.append(row)
        print(
            f"| {path} | "
            + " | ".join(f"{row[c]:+.2f}" if c == "preference" else f"{row[c]:.2f}" for c in cols)
            + " |"
        )
    if len(rows) > 1:
        mean = {c: float(np.mean([r[c] for r in rows])) for c in cols}
        mean["preference"] = float(np.mean([abs(r["preference"]) for r in rows]))
        print(
            "| mean (preference: mean of abs) | "
            + " | ".join(f"{mean[c]:.2f}" for c in cols)
            + " |"
        )


if __name__ == "__main__":
    main(sys.argv[1:])
