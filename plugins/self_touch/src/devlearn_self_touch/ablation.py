"""The curriculum ablation table (paper sec. III-A): one row per evaluated run.

Each run directory holds ``config.json`` (written by ``devlearn run``) and ``eval/eval.json``
(written by ``devlearn eval self_touch ... --json --out RUN/eval``). Usage::

    python -m devlearn_self_touch.ablation runs/ablation_fixed_only runs/ablation_random_only \\
        runs/ablation_two_stage

When some variant was run with several seeds, a second table follows: per curriculum and
budget, the mean over seeds and the range (min-max) of each figure.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from devlearn.api.errors import UsageError
from devlearn.api.json_files import read_json_object

COLUMNS = ("coverage_left", "coverage_right", "coverage_total", "balance", "score")
"""Eval figures shown per run (``devlearn eval self_touch --json``)."""


def ablation_row(run_dir: Path) -> dict[str, Any]:
    """The curriculum, budget and eval figures of one run.

    Raises:
        FileNotFoundError: the run has no ``config.json`` or no ``eval/eval.json``, with the
            command that makes it.
        UsageError: either is unreadable (devlearn's guarded JSON reader) or no JSON object.
    """
    run_dir = Path(run_dir)
    config_file, eval_file = run_dir / "config.json", run_dir / "eval" / "eval.json"
    if not config_file.is_file():
        raise FileNotFoundError(f"{config_file} missing: is {run_dir} a `devlearn run` folder?")
    if not eval_file.is_file():
        raise FileNotFoundError(
            f"{eval_file} missing: run `devlearn eval self_touch --checkpoint "
            f"{run_dir}/checkpoint_latest.pt --episodes 100 --json --out {run_dir}/eval`"
        )
    config = read_json_object(config_file, "a run config")  # devlearn's guarded reader
    result = read_json_object(eval_file, "an evaluation")
    behavior = config.get("behavior") or {}
    curriculum = behavior.get("curriculum", "two_stage")
    if curriculum == "two_stage":
        curriculum += f" (fixed pose for {behavior.get('fixed_pose_steps', 0):,} steps)"
    row = {"run": run_dir.name, "curriculum": curriculum, "steps": config["total_steps"]}
    row.update(seed=config.get("seed", "-"), episodes=result["episodes"])
    row.update({key: result[key] for key in COLUMNS})
    return row


def ablation_table(run_dirs: list[Path]) -> str:
    """A Markdown table of :func:`ablation_row` for each run."""
    header = ["run", "curriculum", "steps", "seed", "episodes", *COLUMNS]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    rows = [ablation_row(run_dir) for run_dir in run_dirs]
    for row in rows:
        cells = [f"{row[k]:,}" if k == "steps" else str(row[k]) for k in header]
        cells[-1] = f"{row['score']:.2f}"
        lines.append("| " + " | ".join(cells) + " |")
    if len({(row["curriculum"], row["steps"]) for row in rows}) < len(rows):
        lines += ["", seed_summary(rows)]
    return "\n".join(lines)


def seed_summary(rows: list[dict[str, Any]]) -> str:
    """A Markdown table: per (curriculum, steps), the mean over seeds and the min-max range."""
    groups: dict[tuple[str, int], list[dict[str, Any]]] = {}
    for row in rows:
        groups.setdefault((row["curriculum"], row["steps"]), []).append(row)
    header = ["curriculum", "steps", "seeds", *(f"{key} mean (min-max)" for key in COLUMNS)]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for (curriculum, steps), members in groups.items():
        cells = [curriculum, f"{steps:,}", str(len(members))]
        for key in COLUMNS:
            values = [float(member[key]) for member in members]
            digits = 2 if key == "score" else 1
            mean, low, high = sum(values) / len(values), min(values), max(values)
            low_high = f"{low:.2f}-{high:.2f}" if key == "score" else f"{low:g}-{high:g}"
            cells.append(f"{mean:.{digits}f} ({low_high})")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", type=Path, help="run directories with eval/eval.json")
    args = parser.parse_args(argv)
    try:
        print(ablation_table(args.runs))
    except (FileNotFoundError, UsageError) as error:
        parser.exit(2, f"error: {error}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
