"""Print the Markdown table of results/self_touch/i20: every evaluated checkpoint of each seed.

Run from the repository root: ``python results/self_touch/i20/checkpoint_table.py``. Each cell
is read from an ``at_<steps>/eval.json`` written by ``devlearn eval`` (100 random-pose episodes,
eval seed 0); nothing is computed here but the layout.
"""

from __future__ import annotations

import json
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


def main() -> None:
    runs = sorted(p for p in HERE.glob("two_stage_s*") if p.is_dir())
    steps = sorted({int(p.name[3:]) for run in runs for p in run.glob("at_*")})
    print("| steps | stage | " + " | ".join(f"seed {r.name[-1]}" for r in runs) + " |")
    print("|---|---|" + "---|" * len(runs))
    for step in steps:
        stage = "fixed pose" if step <= 4_001_792 else "random pose"
        cells = [cell(run / f"at_{step}" / "eval.json") for run in runs]
        print(f"| {step:,} | {stage} | " + " | ".join(cells) + " |")
    for name in ("zero", "random"):
        print(f"| {name} baseline | - | {cell(HERE / f'baseline_{name}' / 'eval.json')} |")


if __name__ == "__main__":
    main()
