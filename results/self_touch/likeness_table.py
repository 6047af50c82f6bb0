"""Issue #43's likeness table: the published self-touch policies (mean and 95% t-interval over
seeds) and the baselines beside the infant figures. Usage:
    python results/self_touch/likeness_table.py OUT   # OUT of results/self_touch/likeness.sh
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from devlearn.api.stats import mean_ci
from devlearn.evaluation.report import cell  # mean [low, high], as devlearn report shows it

MEASURES = (
    ("touches_per_minute", "touches / min"),
    ("distinct_regions_per_minute", "distinct regions / min"),
    ("contact_time_share", "time a hand touches the body"),
    ("mean_seconds_between_touches", "s between touches"),
)
AREAS = ("face", "torso", "arm", "leg", "foot")


def main(out: Path) -> None:
    def likeness(folder: Path) -> dict:
        return json.loads((folder / "eval.json").read_text())["likeness"]

    seeds = [likeness(p) for p in sorted(out.glob("seed=*"))]
    rows = {f"trained ({len(seeds)} seeds)": seeds}
    rows.update({f"{p} actions": [likeness(out / f"baseline_{p}")] for p in ("zero", "random")})
    head = [label for _, label in MEASURES] + [f"share of touches: {a}" for a in AREAS]
    print("| policy | " + " | ".join(head) + " |")
    print("|---" * (len(head) + 1) + "|")
    for name, runs in rows.items():
        cells = []
        for key, _ in MEASURES:
            values = [r[key] for r in runs if r[key] is not None]
            cells.append(cell(mean_ci(values)))
        for area in AREAS:
            values = [r["touch_share_by_area"].get(area, 0.0) for r in runs if r["touches"]]
            cells.append(cell(mean_ci(values)))
        print(f"| {name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
