"""The Markdown table of results/self_touch/i20 (issue #20): every evaluated checkpoint of
some runs.

Run from the repository root (results/self_touch/README.md gives the committed tables)::

    python -m devlearn_self_touch.analysis.checkpoint_table               # two_stage_s1..s3 (8M)
    python -m devlearn_self_touch.analysis.checkpoint_table two_stage_s1 per_env_s1

Each RUN is a folder under ``--folder`` (default ``results/self_touch/i20``) holding
``at_<steps>/eval.json`` files written by ``devlearn eval`` (100 random-pose episodes, eval
seed 0); the last two rows are the folder's ``baseline_zero`` and ``baseline_random``
evaluations. Nothing is computed here but the layout. The stage of a row is the first run's
(from the config recorded in its eval.json).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from devlearn import UsageError

FOLDER = Path("results/self_touch/i20")
"""Issue #20's results, relative to the repository root."""


def cell(path: Path) -> str:
    """``L / R / T, balance, union score; per-episode score [95% CI]`` of one evaluation;
    ``-`` where there is none."""
    if not path.exists():
        return "-"
    e = json.loads(path.read_text())
    return (
        f"{e['coverage_left']} / {e['coverage_right']} / {e['coverage_total']}, "
        f"b {e['balance']}, **{e['score']:.2f}**; {e['episode_score_mean']:.3f} "
        f"[{e['episode_score_ci_low']:.3f}, {e['episode_score_ci_high']:.3f}]"
    )


def stage(run: Path, step: int) -> str:
    """The curriculum stage the run's checkpoint at ``step`` was trained in, last."""
    config = json.loads(next(run.glob("at_*/eval.json")).read_text())["config"]
    behavior = config["behavior"]
    iteration = config["num_envs"] * config["ppo"]["num_steps_per_env"]
    curriculum = behavior.get("curriculum", "two_stage")
    if curriculum != "two_stage":
        return str(curriculum).replace("_only", " pose")
    # the last iteration before the checkpoint started in stage 1: it is stage 1's
    return "fixed pose" if step - iteration < behavior["fixed_pose_steps"] else "random pose"


def table(folder: Path, names: list[str]) -> str:
    """The Markdown table of the runs ``names`` under ``folder`` (all ``two_stage_s<N>`` when
    none are named) and the folder's two baselines.

    Raises:
        UsageError: A run has no ``at_<steps>/eval.json``.
    """
    runs = [folder / n for n in names] or sorted(folder.glob("two_stage_s[0-9]"))
    if not runs:
        raise UsageError(f"{folder} holds no two_stage_s<N> run; name the runs to tabulate")
    for run in runs:
        if next(run.glob("at_*/eval.json"), None) is None:
            raise UsageError(
                f"{run} holds no at_<steps>/eval.json; valid runs are folders of {folder} "
                "with evaluated checkpoints"
            )
    steps = sorted({int(p.name[3:]) for run in runs for p in run.glob("at_*")})
    lines = [
        "| steps | stage | " + " | ".join(r.name for r in runs) + " |",
        "|---|---|" + "---|" * len(runs),
    ]
    for step in steps:
        cells = [cell(run / f"at_{step}" / "eval.json") for run in runs]
        lines.append(f"| {step:,} | {stage(runs[0], step)} | " + " | ".join(cells) + " |")
    for name in ("zero", "random"):
        lines.append(f"| {name} baseline | - | {cell(folder / f'baseline_{name}' / 'eval.json')} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> str:
    """Command line: see the module docstring. Prints the table and returns it."""
    parser = argparse.ArgumentParser(
        prog="python -m devlearn_self_touch.analysis.checkpoint_table",
        description=(__doc__ or "").splitlines()[0],
    )
    parser.add_argument("runs", nargs="*", metavar="RUN", help="run folders under --folder")
    parser.add_argument("--folder", default=str(FOLDER), help="where the runs are")
    args = parser.parse_args(argv)
    markdown = table(Path(args.folder), args.runs)
    print(markdown, end="")
    return markdown


if __name__ == "__main__":
    main()
