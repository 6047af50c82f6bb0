"""Print the Markdown tables of results/hand_regard (issue #29): visibility per eye-hand pair
under the four measures, over seeds, beside the baselines and the paper.

Run from the repository root::

    python results/hand_regard/table.py                  # the published runs (i29/*)
    python results/hand_regard/table.py --readme results/hand_regard/README.md   # in place
    python results/hand_regard/table.py --root sweeps/hr29  # a sweep folder, before publishing

Every number is read from an ``eval.json`` written by ``devlearn eval`` (10 episodes of 1,000
steps, eval seed 0): ``eval/`` from BabyBench's start (the paper-comparable protocol),
``eval_random/`` from random starts (the generalisation row). A group's cell is the mean over
its runs (seeds) with the 95% t-interval over them (``devlearn.api.stats.mean_ci``); the
baselines' cells are single evaluations with the interval over their episodes (``ep``).
Nothing is computed here but means, intervals and the layout.
"""

from __future__ import annotations

import glob
import json
import sys
from pathlib import Path

from devlearn.api.stats import mean_ci

HERE = Path(__file__).resolve().parent
PAIRS = ("left_eye_left_hand", "right_eye_left_hand", "left_eye_right_hand", "right_eye_right_hand")
SHORT = ("LL", "RL", "LR", "RR")
GROUPS = (
    ("paper reward (the control)", "reward=paper,seed=*"),
    ("ours: paper + bilateral term", "reward=bilateral,seed=*"),
    ("ours: paper + bilateral + reach_into_view", "reward=reach,seed=*"),
    ("ours: paper + bilateral + reach_into_view, T = 4", "reward=reach_t4,seed=*"),
    ("paper + forward_model curiosity", "curiosity=forward_model,seed=*"),
    ("paper reward, the paper's CNN policy", "policy=cnn,seed=*"),
    ("paper reward, the paper's CNN actor, asymmetric critic", "policy=cnn,critic=proprio,seed=*"),
)
"""(label, run-folder pattern) of the arms; the folders are found anywhere under the root."""
BASELINES = (("zero", "zero action"), ("random", "random action"), ("held_random", "held random"))
MEASURES = {
    "detector": "the run's calibrated detector (the paper's measure: % of steps with a detection)",
    "pixels": "ground truth: >= 20 pixels of the hand in the eye's segmentation render",
    "babybench": "BabyBench's official counter: the eye body's -z axis within 15 degrees",
    "cone": "the hand's centre within 15 degrees of the camera's optical axis (stricter centring)",
}
PAPER_TRAINING_SCORE = 0.279
"""The paper's hand-regard "training score": BabyBench's counter (``babybench``)."""


def runs(root: Path, pattern: str, folder: str = "eval") -> list[dict]:
    """The ``folder/eval.json`` of every run folder under ``root`` named like ``pattern``."""
    found = sorted(glob.glob(str(root / "**" / pattern / folder / "eval.json"), recursive=True))
    return [{**json.loads(Path(f).read_text()), "_folder": Path(f).parent.parent} for f in found]


def cell(values: list[float]) -> str:
    """``mean [low, high]`` over ``values`` (just the mean when there is one)."""
    s = mean_ci(values)
    if s["mean"] is None:
        return "-"
    if s["ci_low"] is None:
        return f"{s['mean']:.3f}"
    return f"{s['mean']:.3f} [{s['ci_low']:.3f}, {s['ci_high']:.3f}]"


def episode_cell(e: dict, measure: str) -> str:
    """One evaluation's average with its interval over episodes."""
    c = e["criteria"][measure]
    low, high = c["episode_average_ci_low"], c["episode_average_ci_high"]
    if low is None:
        return f"{c['average']:.3f}"
    return f"{c['average']:.3f} [{low:.3f}, {high:.3f}] ep"


def visibility_table(root: Path, measure: str, folder: str, start: str) -> list[str]:
    """One measure's table: the arms over seeds, the baselines, the paper where comparable."""
    rows = [
        f"| `{measure}`, from {start} starts | n | " + " | ".join(SHORT) + " | average [95% CI] |",
        "|---|---|" + "---|" * (len(PAIRS) + 1),
    ]
    for label, pattern in GROUPS:
        found = runs(root, pattern, folder)
        if not found:
            continue
        pairs = [cell([e["criteria"][measure]["visibility"][p] for e in found]) for p in PAIRS]
        average = cell([e["criteria"][measure]["average"] for e in found])
        rows.append(f"| {label} | {len(found)} | " + " | ".join(pairs) + f" | **{average}** |")
    for name, label in BASELINES:
        path = root / f"baseline_{name}_{start}" / "eval.json"
        if path.is_file():
            e = json.loads(path.read_text())
            pairs = [f"{e['criteria'][measure]['visibility'][p]:.3f}" for p in PAIRS]
            rows.append(
                f"| {label} (baseline) | 1 | "
                + " | ".join(pairs)
                + f" | {episode_cell(e, measure)} |"
            )
    if measure == "detector" and start == "babybench":
        paper = (0.996, 0.985, 0.000, 0.044)
        rows.append(
            "| paper, Table III (1.85M steps; its own detector) | - | "
            + " | ".join(f"{v:.3f}" for v in paper)
            + " | 0.506 |"
        )
    if measure == "babybench" and start == "babybench":
        rows.append(
            f"| paper's training score (BabyBench's counter, over training) | - | - | - | - | - "
            f"| {PAPER_TRAINING_SCORE:.3f} |"
        )
    return rows


def per_run_table(root: Path) -> list[str]:
    """Each run: seed, steps, the pairs under `detector` and `pixels` and the four averages from
    BabyBench's start, the largest share of steps a pair is credited while its hand is not in
    view under `pixels` (under 20 of its pixels: detected share x (1 - precision)), the
    generalisation average, and the commit it was evaluated on."""
    rows = [
        "| arm | seed | steps | detector LL / RL / LR / RR | `pixels` LL / RL / LR / RR | detector "
        "| pixels | babybench | cone | steps a pair is credited, its hand not in `pixels`, worst "
        "| detector, random starts | evaluated on |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for label, pattern in GROUPS:
        for e in runs(root, pattern):
            pairs = " | ".join(
                " / ".join(f"{e['criteria'][m]['visibility'][p]:.3f}" for p in PAIRS)
                for m in ("detector", "pixels")
            )
            averages = [f"{e['criteria'][m]['average']:.3f}" for m in MEASURES]
            other = e["_folder"] / "eval_random" / "eval.json"
            general = (
                f"{json.loads(other.read_text())['criteria']['detector']['average']:.3f}"
                if other.is_file()
                else "-"
            )
            code = (e["protocol"].get("code") or {}).get("commit") or "?"
            absent = max(  # detected, and the hand shows fewer than 20 pixels in that eye
                e["criteria"]["detector"]["visibility"][p]
                * (1 - (e["detector_agreement"][p]["precision"] or 0.0))
                for p in PAIRS
            )
            rows.append(
                f"| {label} | {e['training_seed']} | {e['checkpoint_env_steps']:,} | {pairs} | "
                + " | ".join(averages)
                + f" | {100 * absent:.1f}% | {general} | {code[:7]} |"
            )
    return rows


def detector_table(root: Path) -> list[str]:
    """The detector's precision / recall per pair against ``pixels``, pooled over a group's
    evaluations (mean of the runs' values where defined)."""
    rows = [
        "| detector vs `pixels`: precision / recall | n | " + " | ".join(SHORT) + " | average |",
        "|---|---|" + "---|" * (len(PAIRS) + 1),
    ]
    for label, pattern in GROUPS:
        found = runs(root, pattern)
        if not found:
            continue
        cells = []
        for p in [*PAIRS, "average"]:
            agree = [e["detector_agreement"][p] for e in found]
            prec = [a["precision"] for a in agree if a["precision"] is not None]
            rec = [a["recall"] for a in agree if a["recall"] is not None]
            mp = f"{mean_ci(prec)['mean']:.2f}" if prec else "-"
            mr = f"{mean_ci(rec)['mean']:.2f}" if rec else "-"
            cells.append(f"{mp} / {mr}")
        rows.append(f"| {label} | {len(found)} | " + " | ".join(cells) + " |")
    return rows


BOTH_HANDS = 0.5, 0.8
"""Issue #39's target beyond the paper: every pair at least 0.5 and the average at least 0.8."""
ONE_HAND = 0.9
"""The paper's one-hand pattern: one hand in both eyes at least 0.9 of the steps."""


def pattern(e: dict, measure: str) -> str:
    """``both`` (issue #39's target met), ``one`` (one hand >= 0.9 in both eyes, the target not
    met) or ``-``, for one evaluation under ``measure``."""
    v = e["criteria"][measure]["visibility"]
    if (
        min(v[p] for p in PAIRS) >= BOTH_HANDS[0]
        and e["criteria"][measure]["average"] >= BOTH_HANDS[1]
    ):
        return "both"
    hands = (PAIRS[:2], PAIRS[2:])  # each hand in the left eye and the right
    return "one" if any(min(v[a], v[b]) >= ONE_HAND for a, b in hands) else "-"


def patterns_table(root: Path) -> list[str]:
    """Per arm, how many seeds show each pattern from BabyBench's start: both hands (every pair
    >= 0.5, average >= 0.8) under `pixels`, under `detector` and under both; one hand (>= 0.9 in
    both eyes) under `pixels`."""
    rows = [
        "| seeds showing, from babybench starts | n | both hands, `pixels` | both hands, "
        "`detector` | both hands, both measures | one hand >= 0.9 in both eyes, `pixels` |",
        "|---|---|---|---|---|---|",
    ]
    for label, pat in GROUPS:
        found = runs(root, pat)
        if not found:
            continue
        pixels = [pattern(e, "pixels") for e in found]
        detector = [pattern(e, "detector") for e in found]
        both = sum(p == d == "both" for p, d in zip(pixels, detector))
        rows.append(
            f"| {label} | {len(found)} | {pixels.count('both')} | {detector.count('both')} | "
            f"{both} | {pixels.count('one')} |"
        )
    return rows


BEGIN, END = "<!-- table.py begin -->", "<!-- table.py end -->"
"""Markers of the block ``--readme`` rewrites."""


def tables(root: Path) -> str:
    """Every table, in the README's order."""
    blocks = [visibility_table(root, m, "eval", "babybench") for m in MEASURES]
    blocks.append(visibility_table(root, "detector", "eval_random", "random"))
    blocks.append(visibility_table(root, "pixels", "eval_random", "random"))
    blocks += [patterns_table(root), detector_table(root), per_run_table(root)]
    return "\n\n".join("\n".join(rows) for rows in blocks if len(rows) > 2)


def main(argv: list[str]) -> None:
    root = HERE / "i29"
    if argv[:1] == ["--root"]:
        if len(argv) < 2:
            sys.exit("--root needs a folder")
        root, argv = Path(argv[1]), argv[2:]
    if argv[:1] != ["--readme"]:
        print(tables(root))
        return
    if len(argv) < 2:
        sys.exit("--readme needs the README's path")
    readme = Path(argv[1])
    text = readme.read_text()
    if BEGIN not in text or END not in text:
        sys.exit(f"{readme} has no {BEGIN} ... {END} block to rewrite")
    head, rest = text.split(BEGIN, 1)
    tail = rest.split(END, 1)[1]
    readme.write_text(f"{head}{BEGIN}\n{tables(root)}\n{END}{tail}")
    print(f"rewrote the tables in {readme}")


if __name__ == "__main__":
    main(sys.argv[1:])
