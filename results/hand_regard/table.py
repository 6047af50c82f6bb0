"""Print the Markdown tables of results/hand_regard: visibility per eye-hand pair over seeds.

Run from the repository root::

    python results/hand_regard/table.py                      # the issue-19 runs (i19/*)
    python results/hand_regard/table.py --readme results/hand_regard/README.md   # in place
    python results/hand_regard/table.py "paper reward=results/hand_regard/i19/reward=paper,*" \
        "paper + forward_model=results/curiosity/i18/*"     # any groups: LABEL=GLOB

Every number is read from an ``eval.json`` written by ``devlearn eval`` (10 episodes of 1,000
steps from seeded random starts, eval seed 0): a group's cell is the mean over its runs
(seeds) and the 95% t-interval over them (``devlearn.stats.mean_ci``, as ``devlearn report``);
the baselines' cells are their single evaluations with the interval over episodes (marked
``ep``). Nothing is computed here but means, intervals and the layout.
"""

from __future__ import annotations

import glob
import json
import sys
from pathlib import Path

from devlearn.stats import mean_ci

HERE = Path(__file__).resolve().parent
PAIRS = ("left_eye_left_hand", "right_eye_left_hand", "left_eye_right_hand", "right_eye_right_hand")
SHORT = ("LL", "RL", "LR", "RR")
DEFAULT_GROUPS = (
    "paper reward (no bilateral term)=results/hand_regard/i19/reward=paper,seed=*",
    "ours: paper + bilateral term=results/hand_regard/i19/reward=bilateral,seed=*",
)
BASELINES = ("zero", "random")
HISTORICAL = HERE / "run" / "eval" / "eval.json"
"""The first published run (76.8k steps, bilateral reward, one seed), kept as a labelled row."""


def evals(pattern: str) -> list[dict]:
    """The eval JSONs of the run folders (or eval folders) matching ``pattern``, by path."""
    files = []
    for folder in sorted(glob.glob(pattern)):
        path = Path(folder)
        candidates = [path / "eval.json", path / "eval" / "eval.json"]
        files += [(path, c) for c in candidates if c.is_file()][:1]
    return [{**json.loads(f.read_text()), "_folder": folder} for folder, f in files]


def training_commits(e: dict) -> str:
    """The code commits the run trained on (its sweep record's attempts), short, in order."""
    record = e["_folder"] / "sweep_record.json"
    if not record.is_file():
        return "?"
    commits = []
    for attempt in json.loads(record.read_text()).get("attempts", []):
        if attempt.get("phase") in ("train", "resume") and attempt.get("commit"):
            short = attempt["commit"][:7] + ("+dirty" if attempt.get("dirty") else "")
            commits += [short] if short not in commits else []
    return ", ".join(commits) or "?"


def cell(values: list[float]) -> str:
    """``mean [low, high]`` over ``values`` (just the mean when there is one)."""
    s = mean_ci(values)
    if s["mean"] is None:
        return "-"
    if s["ci_low"] is None:
        return f"{s['mean']:.3f}"
    return f"{s['mean']:.3f} [{s['ci_low']:.3f}, {s['ci_high']:.3f}]"


def episode_cell(e: dict, criterion: str) -> str:
    """One evaluation's average with its interval over episodes."""
    c = e["criteria"][criterion]
    low, high = c["episode_average_ci_low"], c["episode_average_ci_high"]
    return f"{c['average']:.3f} [{low:.3f}, {high:.3f}] ep"


def pair_cells(c: dict) -> list[str]:
    """One evaluation's visibility per eye-hand pair (a criterion's entry), in PAIRS order."""
    return [f"{c['visibility'][p]:.3f}" for p in PAIRS]


def visibility_table(groups: list[tuple[str, list[dict]]], criterion: str) -> list[str]:
    head = " | ".join(SHORT)
    rows = [
        f"| `{criterion}` | n | {head} | average [95% CI] |",
        "|---|---|" + "---|" * (len(PAIRS) + 1),
    ]
    for label, runs in groups:
        pairs = [cell([e["criteria"][criterion]["visibility"][p] for e in runs]) for p in PAIRS]
        average = cell([e["criteria"][criterion]["average"] for e in runs])
        rows.append(f"| {label} | {len(runs)} | " + " | ".join(pairs) + f" | **{average}** |")
    singles = [(f"{n} action (baseline)", HERE / f"baseline_{n}" / "eval.json") for n in BASELINES]
    singles.append(("historical: first run, 76.8k steps, 1 seed", HISTORICAL))
    for label, path in singles:
        if path.is_file():
            e = json.loads(path.read_text())
            pairs = pair_cells(e["criteria"][criterion])
            rows.append(
                f"| {label} | 1 | " + " | ".join(pairs) + f" | {episode_cell(e, criterion)} |"
            )
    paper = json.loads(HISTORICAL.read_text())["paper"] if HISTORICAL.is_file() else None
    if criterion == "cone" and paper:
        rows.append(
            "| paper, Table III (1.85M steps; its own criterion) | - | "
            + " | ".join(pair_cells(paper))
            + f" | {paper['average']:.3f} |"
        )
    return rows


def per_run_table(groups: list[tuple[str, list[dict]]]) -> list[str]:
    rows = [
        "| group | seed | steps | cone LL / RL / LR / RR | cone average [95% CI, episodes] "
        "| pixels average | trained on | evaluated on |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for label, runs in groups:
        for e in runs:
            pairs = " / ".join(pair_cells(e["criteria"]["cone"]))
            code = (e["protocol"].get("code") or {}).get("commit") or "?"
            rows.append(
                f"| {label} | {e['training_seed']} | {e['checkpoint_env_steps']:,} | {pairs} "
                f"| {episode_cell(e, 'cone').removesuffix(' ep')} "
                f"| {e['criteria']['pixels']['average']:.3f} | {training_commits(e)} | {code[:7]} |"
            )
    return rows


def detector_table(groups: list[tuple[str, list[dict]]]) -> list[str]:
    rows = [
        "| detector vs truth (`any_pixel`), precision / recall | n | " + " | ".join(SHORT) + " |",
        "|---|---|" + "---|" * len(PAIRS),
    ]
    for label, runs in groups:
        cells = []
        for p in PAIRS:
            agree = [e["detector_agreement"][p] for e in runs]
            prec = [a["precision"] for a in agree if a["precision"] is not None]
            rec = [a["recall"] for a in agree if a["recall"] is not None]
            mp = f"{mean_ci(prec)['mean']:.2f}" if prec else "-"
            mr = f"{mean_ci(rec)['mean']:.2f}" if rec else "-"
            cells.append(f"{mp} / {mr}")
        rows.append(f"| {label} | {len(runs)} | " + " | ".join(cells) + " |")
    return rows


def rest_table(groups: list[tuple[str, list[dict]]]) -> list[str]:
    """The diagnostic from the rest pose (``devlearn eval --start rest``, one episode: a
    deterministic policy repeats it), per run, with the baselines from the same start; empty
    when no run has an ``eval_rest/eval.json``."""
    rows = [
        "| from the rest pose (1 episode) | seed | cone LL / RL / LR / RR | cone average "
        "| pixels LL / RL / LR / RR | pixels average |",
        "|---|---|---|---|---|---|",
    ]

    def row(label: str, seed: str, e: dict) -> str:
        cells = []
        for criterion in ("cone", "pixels"):
            c = e["criteria"][criterion]
            cells += [" / ".join(pair_cells(c)), f"{c['average']:.3f}"]
        return f"| {label} | {seed} | " + " | ".join(cells) + " |"

    for label, runs in groups:
        for e in runs:
            path = Path(e["_folder"]) / "eval_rest" / "eval.json"
            if path.is_file():
                rows.append(row(label, str(e["training_seed"]), json.loads(path.read_text())))
    if len(rows) == 2:
        return []
    for name in BASELINES:
        path = HERE / f"baseline_{name}_rest" / "eval.json"
        if path.is_file():
            rows.append(row(f"{name} action (baseline)", "-", json.loads(path.read_text())))
    return rows


BEGIN, END = "<!-- table.py begin -->", "<!-- table.py end -->"
"""Markers of the block ``--readme`` rewrites."""


def tables(specs: list[str]) -> str:
    """The tables (five with rest-pose evaluations) for the groups ``LABEL=GLOB``
    (default: :data:`DEFAULT_GROUPS`)."""
    groups = []
    for spec in specs or DEFAULT_GROUPS:
        label, sep, pattern = spec.partition("=")
        if not sep:
            sys.exit(f"group {spec!r}: write LABEL=GLOB (e.g. 'paper=results/hand_regard/i19/*')")
        runs = evals(pattern)
        if not runs:
            sys.exit(f"group {label!r}: no eval.json under {pattern!r}")
        groups.append((label, runs))
    blocks = [visibility_table(groups, c) for c in ("cone", "pixels")]
    blocks += [per_run_table(groups), detector_table(groups), rest_table(groups)]
    return "\n\n".join("\n".join(rows) for rows in blocks if rows)


def main(argv: list[str]) -> None:
    if argv[:1] != ["--readme"]:
        print(tables(argv))
        return
    if len(argv) < 2:
        sys.exit("--readme needs the README's path")
    readme = Path(argv[1])
    text = readme.read_text()
    if BEGIN not in text or END not in text:
        sys.exit(f"{readme} has no {BEGIN} ... {END} block to rewrite")
    head, rest = text.split(BEGIN, 1)
    tail = rest.split(END, 1)[1]
    readme.write_text(f"{head}{BEGIN}\n{tables(argv[2:])}\n{END}{tail}")
    print(f"rewrote the tables in {readme}")


if __name__ == "__main__":
    main(sys.argv[1:])
