"""Print the Markdown table of results/self_touch/i20: every evaluated checkpoint of some runs.

Run from the repository root::

    python results/self_touch/i20/checkpoint_table.py                  # two_stage_s1..s3 (8M)
    python results/self_touch/i20/checkpoint_table.py two_stage_s1 per_env_s1

Each cell is read from an ``at_<steps>/eval.json`` written by ``devlearn eval`` (100
random-pose episodes, eval seed 0); nothing is computed here but the layout. The stage of a
row is the first run's (from the config recorded in its eval.json).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def cell(path: Path) -> str:
    """``L / R / T, balance, union score; per-episode score [95% CI]`` of one evaluation."""
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
    behavior, iteration = config["behavior"], config["num_envs"] * config["ppo"]["num_steps_per_env"]
    curriculum = behavior.get("curriculum", "two_stage")
    if curriculum != "two_stage":
        return curriculum.replace("_only", " pose")
    # the last iteration before the checkpoint started in stage 1: it is stage 1's
    return "fixed pose" if step - iteration < behavior["fixed_pose_steps"] else "random pose"


def main(names: list[str]) -> None:
    runs = [HERE / n for n in names] or sorted(HERE.glob("two_stage_s[0-9]"))
    steps = sorted({int(p.name[3:]) for run in runs for p in run.glob("at_*")})
    print("| steps | stage | " + " | ".join(r.name for r in runs) + " |")
    print("|---|---|" + "---|" * len(runs))
    for step in steps:
        cells = [cell(run / f"at_{step}" / "eval.json") for run in runs]
        print(f"| {step:,} | {stage(runs[0], step)} | " + " | ".join(cells) + " |")
    for name in ("zero", "random"):
        print(f"| {name} baseline | - | {cell(HERE / f'baseline_{name}' / 'eval.json')} |")


if __name__ == "__main__":
    main(sys.argv[1:])
