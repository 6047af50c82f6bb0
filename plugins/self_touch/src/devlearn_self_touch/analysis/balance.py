"""What drives the per-episode imbalance |left - right| of self-touch policies (issue #43,
item 2).

Run from the repository root (results/self_touch/README.md gives the committed arguments)::

    python -m devlearn_self_touch.analysis.balance EVAL_JSON [EVAL_JSON ...]

For each evaluation (an ``eval.json`` written by ``devlearn eval self_touch``), prints the
parts each hand touches per episode and splits the mean imbalance E|L - R| into its two
sources:

- **a hand preference** of the policy: the mean signed difference mean(L - R), the same in every
  episode (a seed that learned to explore more with one hand);
- **episode-to-episode spread**: each hand's coverage varies with the start pose, and the two
  hands vary partly independently (corr(L, R)).

``without preference`` is E|d - round(mean d)|: the imbalance left if the policy's constant
hand preference were removed; ``hands independent`` is E|L - R'| with R shuffled across
episodes (the imbalance if the hands' coverages were unrelated), for scale. ``bonus paid`` is
the share of episodes whose |L - R| <= 3, the balance term's tolerance (R_balance pays then).
With more than one evaluation, a last row gives their mean (of the preference's size).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from devlearn import UsageError

TOLERANCE = 3
"""The balance term's tolerance (``behavior.rewards.balance.params.tolerance``) and issue #43's
target for the mean per-episode balance."""

COLUMNS = (
    "left",
    "right",
    "balance",
    "preference",
    "without_preference",
    "corr",
    "independent",
    "bonus_paid",
)
"""The table's figures, in order (the keys of :func:`decompose`'s result)."""


def episode_parts(doc: dict[str, Any], source: str = "eval.json") -> list[dict[str, list[int]]]:
    """The per-episode touched parts per hand (``episode_parts``), wherever the eval JSON
    nests them.

    Raises:
        UsageError: ``doc`` holds no ``episode_parts`` (not a self-touch evaluation).
    """
    stack: list[Any] = [doc]
    while stack:
        node = stack.pop()
        if isinstance(node, dict):
            if "episode_parts" in node:
                return list(node["episode_parts"])
            stack.extend(node.values())
    raise UsageError(
        f"{source} holds no 'episode_parts'; give an eval.json written by "
        "`devlearn eval self_touch`"
    )


def _corr(a: np.ndarray, b: np.ndarray) -> float:
    """Pearson's correlation; NaN when a hand's coverage never varies (e.g. zero actions)."""
    if a.std() == 0 or b.std() == 0:
        return float("nan")
    return float(np.corrcoef(a, b)[0, 1])


def decompose(episodes: list[dict[str, list[int]]], seed: int = 0) -> dict[str, float]:
    """The imbalance of one evaluation and its sources (see the module docstring).

    Args:
        episodes: Per episode, the parts each hand touched (``{"left": [...], "right": [...]}``).
        seed: Seed of the 200 shuffles behind ``independent``.

    Raises:
        UsageError: ``episodes`` is empty.
    """
    if not episodes:
        raise UsageError("no episodes to decompose; the evaluation's 'episode_parts' is empty")
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


def table(rows: dict[str, dict[str, float]]) -> str:
    """The Markdown table of :func:`decompose` results by label (one row each, and their mean
    when there are several: the preference's as the mean of its absolute value)."""
    lines = [
        "| eval | " + " | ".join(c.replace("_", " ") for c in COLUMNS) + " |",
        "|---" * (len(COLUMNS) + 1) + "|",
    ]
    for label, row in rows.items():
        cells = (f"{row[c]:+.2f}" if c == "preference" else f"{row[c]:.2f}" for c in COLUMNS)
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    if len(rows) > 1:
        mean = {c: float(np.mean([r[c] for r in rows.values()])) for c in COLUMNS}
        mean["preference"] = float(np.mean([abs(r["preference"]) for r in rows.values()]))
        lines.append(
            "| mean (preference: mean of abs) | "
            + " | ".join(f"{mean[c]:.2f}" for c in COLUMNS)
            + " |"
        )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> dict[str, dict[str, float]]:
    """Command line: see the module docstring. Prints the table; returns each evaluation's
    figures by its path."""
    parser = argparse.ArgumentParser(
        prog="python -m devlearn_self_touch.analysis.balance",
        description=(__doc__ or "").splitlines()[0],
    )
    parser.add_argument("evals", nargs="+", metavar="EVAL_JSON", help="self-touch eval.json")
    args = parser.parse_args(argv)
    rows: dict[str, dict[str, float]] = {}
    for path in args.evals:
        try:
            doc = json.loads(Path(path).read_text())
        except (OSError, json.JSONDecodeError) as error:
            raise UsageError(f"cannot read {path} as an eval.json: {error}") from error
        rows[path] = decompose(episode_parts(doc, path))
    print(table(rows), end="")
    return rows


if __name__ == "__main__":
    main()
