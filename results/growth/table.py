"""Issue #41's table from what ``experiment.sh`` wrote: ``python results/growth/table.py OUT``.

Rows: the arms (fixed6, fixed12, fixed18: a body of one age throughout; grow6to18: growing over
the run) and the zero and random baselines; columns: the body's age at evaluation (6, 12, 18
months). Each cell is the per-episode self-touch score (parts touched per episode by both
hands / 68, the mean over the evaluation's episodes) as the mean and 95% t-interval over seeds;
an arm's own age (18 months for the growing arm) is its headline, the other ages its transfer.
Then the question of the issue: growing minus fixed18 at 18 months (Welch's interval of the
difference of means over seeds), and each arm's seeds.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

from scipy import stats

from devlearn.api.stats import mean_ci

AGES = (6, 12, 18)


def _arms(out: Path) -> dict[str, dict[int, list[float]]]:
    """Arm -> evaluated age -> per-episode scores of its seeds (in seed order)."""
    arms: dict[str, dict[int, list[float]]] = {}
    for run in sorted((out / "fixed" / "runs").glob("*")) + sorted(
        (out / "grow" / "runs").glob("*")
    ):
        fixed = re.match(r"age_months=(\d+)", run.name)
        arm = f"fixed{fixed.group(1)}" if fixed else "grow6to18"
        for age in AGES:
            path = run / f"at_{age}_months" / "eval.json"
            if path.exists():
                score = json.loads(path.read_text())["episode_score_mean"]
                arms.setdefault(arm, {}).setdefault(age, []).append(score)
    return arms


def _cell(values: list[float], own: bool) -> str:
    if not values:
        return "-"
    s = mean_ci(values)
    text = f"{s['mean']:.3f}" + (
        f" [{s['ci_low']:.3f}, {s['ci_high']:.3f}]" if s["ci_low"] is not None else ""
    )
    text += f" (n={len(values)})"
    return f"**{text}**" if own else text


def main(out: Path) -> None:
    arms = _arms(out)
    own = {"fixed6": 6, "fixed12": 12, "fixed18": 18, "grow6to18": 18}
    print("| policy | " + " | ".join(f"at {a} months" for a in AGES) + " |")
    print("|---" * (len(AGES) + 1) + "|")
    for arm in ("fixed6", "fixed12", "fixed18", "grow6to18"):
        if arm in arms:
            cells = [_cell(arms[arm].get(a, []), own[arm] == a) for a in AGES]
            print(f"| {arm} | " + " | ".join(cells) + " |")
    for policy in ("zero", "random"):
        cells = []
        for age in AGES:
            path = out / f"baseline_{policy}_{age}_months" / "eval.json"
            cells.append(
                f"{json.loads(path.read_text())['episode_score_mean']:.3f}"
                if path.exists()
                else "-"
            )
        print(f"| {policy} actions | " + " | ".join(cells) + " |")
    grow = arms.get("grow6to18", {}).get(18, [])
    fixed = arms.get("fixed18", {}).get(18, [])
    if len(grow) >= 2 and len(fixed) >= 2:
        test = stats.ttest_ind(grow, fixed, equal_var=False)
        ci = test.confidence_interval()
        diff = sum(grow) / len(grow) - sum(fixed) / len(fixed)
        print(
            f"\ngrowing - fixed18 at 18 months: {diff:+.3f} [{ci.low:+.3f}, {ci.high:+.3f}] "
            f"(Welch, p = {test.pvalue:.3f}; {len(grow)} and {len(fixed)} seeds)"
        )
    print("\nPer seed (at each arm's own age):")
    for arm, ages in arms.items():
        print(f"- {arm}: " + ", ".join(f"{v:.3f}" for v in ages.get(own[arm], [])))


if __name__ == "__main__":
    if len(sys.argv) != 2:
        raise SystemExit(__doc__)
    main(Path(sys.argv[1]))
