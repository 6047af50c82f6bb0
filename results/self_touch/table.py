"""Issue #30's tables and evaluation curve from the eval JSONs that ``curriculum.sh`` and
``ablation.sh`` write: ``python results/self_touch/table.py curriculum|ablation OUT``.

``curriculum OUT``: OUT/runs/seed=N/ run folders (``eval/eval.json`` the final checkpoint's
random-pose evaluation, ``at_STEP/eval.json`` the earlier checkpoints', ``rest/eval.json`` the
final checkpoint from the rest pose, ``metrics.jsonl`` the training log) and
OUT/baseline_{zero,random}[_rest]/eval.json. Prints the headline table (over seeds), the
per-seed table, the evaluation curve (mean over seeds at every step) and the median seed, and
draws OUT/eval_curve.png (one line per seed, baselines as horizontal lines).

``ablation OUT``: OUT/runs/curriculum=ARM,seed=N/ run folders and the same baselines; prints one
row per arm, the paper's Table II and the difference of every pair of arms.

``pilots OUT``: issue #43's pilots (``pilots43.sh``): OUT/PILOT/seed=N/ run folders (PILOT
control, balance, repeats or rate) and OUT/baseline_{zero,random}/; prints the headline table, the
balance's sources (``balance.py``), the likeness measures (``likeness_table.py``) and each
pilot's difference from the control.

The headline is the per-episode score ((left + right) parts touched in an episode / 68,
averaged over the 100 episodes): mean and 95% t-interval over seeds, then each seed's own
t-interval over its episodes. The union score (each hand's parts over all 100 episodes,
the paper's "evaluation score") has each seed's 95% bootstrap interval over episodes,
recomputed from the eval JSON's ``episode_parts``. The training score is the run's last
``metrics/training_score`` (BabyBench's: the union per hand over the last 10,000 training
episodes), the paper's 0.88.
"""

from __future__ import annotations

import itertools
import json
import statistics
import sys
from pathlib import Path
from typing import Any

from devlearn_self_touch.evaluation import PAPER_RESULTS, union_score, union_score_interval

from devlearn.api.stats import mean_ci

sys.path.insert(0, str(Path(__file__).parent))  # balance.py and likeness_table.py beside it
from balance import decompose  # noqa: E402
from likeness_table import AREAS, MEASURES  # noqa: E402

PAPER_TRAINING_SCORE = {"two_stage": 0.88, "fixed_only": 0.85, "random_only": 0.75}
"""The paper's training scores (Table I: 0.88; Table II "Train")."""


def _load(path: Path) -> dict[str, Any] | None:
    return json.loads(path.read_text()) if path.exists() else None


def _ci(values: list[float], digits: int = 3) -> str:
    values = [v for v in values if v is not None]
    if not values:
        return "-"
    s = mean_ci(values)
    if s["ci_low"] is None:
        return f"{s['mean']:.{digits}f}"
    return f"{s['mean']:.{digits}f} [{s['ci_low']:.{digits}f}, {s['ci_high']:.{digits}f}]"


def _own(e: dict[str, Any], key: str, digits: int = 3) -> str:
    """One evaluation's per-episode mean of ``key`` with its t-interval over episodes."""
    mean = e.get(f"episode_{key}_mean")
    if mean is None:
        return "-"
    low, high = e.get(f"episode_{key}_ci_low"), e.get(f"episode_{key}_ci_high")
    if low is None:
        return f"{mean:.{digits}f}"
    return f"{mean:.{digits}f} [{low:.{digits}f}, {high:.{digits}f}]"


def union(e: dict[str, Any]) -> tuple[float, float | None, float | None]:
    """The union score and its 95% bootstrap interval, recomputed from ``episode_parts``
    when the JSON has them (else its stored score and interval)."""
    parts = e.get("episode_parts")
    if parts:
        boot = union_score_interval(parts)
        return union_score(parts), boot["score_boot_low"], boot["score_boot_high"]
    return e["score"], e.get("score_boot_low"), e.get("score_boot_high")


def _union_text(e: dict[str, Any]) -> str:
    score, low, high = union(e)
    return f"{score:.2f}" if low is None else f"{score:.2f} [{low:.2f}, {high:.2f}]"


def training_score(run: Path) -> float | None:
    """The last ``metrics/training_score`` in ``run/metrics.jsonl`` (None if never logged)."""
    path = run / "metrics.jsonl"
    if not path.exists():
        return None
    last = None
    for line in path.read_text().splitlines():
        last = json.loads(line).get("metrics/training_score", last)
    return last


def _never(e: dict[str, Any]) -> str:
    """Parts no hand touched in the evaluation: their names when few, else their number."""
    names = e.get("parts_never_touched", [])
    return ", ".join(names) if 0 < len(names) <= 6 else str(len(names))


def _seed(run: Path) -> str:
    return run.name.rsplit("seed=", 1)[1]


def curve(run: Path) -> dict[int, dict[str, Any]]:
    """Step -> random-pose evaluation of the checkpoint at that step (``at_STEP`` and the
    final one in ``eval/``)."""
    points = {int(p.parent.name[3:]): _load(p) for p in run.glob("at_*/eval.json")}
    final = _load(run / "eval" / "eval.json")
    if final is not None:
        points[int(final["checkpoint_env_steps"])] = final
    return dict(sorted(points.items()))


COVERAGE = ("coverage_left", "coverage_right", "coverage_total")

HEADLINE = (
    "| | seeds | **per-episode score** | per seed (own 95% interval over episodes) "
    "| coverage left / right / total (per episode) | balance (per episode) "
    "| union score (per seed: 95% bootstrap) | union parts left / right / total "
    "| training score (last 10,000 episodes) |\n|---|---|---|---|---|---|---|---|---|"
)


def group_row(label: str, evals: list[dict[str, Any]], train: list[float | None]) -> str:
    """One row of :data:`HEADLINE` over seeds' evaluations (a baseline: one evaluation)."""

    def over(key: str, digits: int = 3) -> str:
        return _ci([e.get(f"episode_{key}_mean") for e in evals], digits)

    return "| " + " | ".join([
        label,
        str(len(evals)) if len(evals) > 1 or train else "-",
        f"**{over('score')}**",
        ", ".join(_own(e, "score") for e in evals) if len(evals) > 1 else "-",
        " / ".join(over(k, 1) for k in COVERAGE),
        over("balance", 1),
        _union_text(evals[0])
        if len(evals) == 1
        else f"{_ci([union(e)[0] for e in evals], 2)} ("
        + ", ".join(_union_text(e) for e in evals)
        + ")",
        " / ".join(_ci([e[k] for e in evals], 1) for k in COVERAGE),
        _ci(train) if train else "-",
    ]) + " |"  # fmt: skip


def _baseline_rows(out: Path) -> list[str]:
    rows = []
    for suffix, where in (("", "random poses"), ("_k10", "random poses"), ("_rest", "rest pose")):
        for policy in ("zero", "random"):
            e = _load(out / f"baseline_{policy}{suffix}" / "eval.json")
            if e is not None:
                repeat = e["protocol"].get("action_repeat", 1)
                label = f"{policy} actions (held {repeat} physics steps), {where}"
                rows.append(group_row(label, [e], []))
    return rows


def _paper_row(curriculum: str) -> str:
    label, paper = PAPER_RESULTS[curriculum]
    left, right = paper.get("coverage_left", "-"), paper.get("coverage_right", "-")
    return (
        f"| {label}, its protocol | - | - | - | - | - "
        f"| {paper['score']:.2f} | {left} / {right} / {paper['coverage_total']} "
        f"| {PAPER_TRAINING_SCORE[curriculum]:.2f} |"
    )


def median_seed(runs: list[Path]) -> Path:
    """The seed whose final per-episode score is the median (the lower one of an even count)."""
    ranked = sorted(runs, key=lambda r: curve(r)[max(curve(r))]["episode_score_mean"])
    return ranked[(len(ranked) - 1) // 2]


def curriculum_tables(out: Path) -> str:
    runs = [r for r in out.glob("runs/seed=*") if (r / "eval" / "eval.json").exists()]
    runs.sort(key=lambda r: int(_seed(r)))
    if not runs:
        raise SystemExit(f"no finished runs (runs/seed=N/eval/eval.json) in {out}")
    finals = [_load(r / "eval" / "eval.json") for r in runs]
    rests = [e for r in runs if (e := _load(r / "rest" / "eval.json")) is not None]
    trains = [training_score(r) for r in runs]
    steps = finals[0]["checkpoint_env_steps"]
    lines = [f"### Final checkpoint ({steps:,} steps)\n", HEADLINE]
    lines.append(group_row("two-stage, random poses", finals, trains))
    if rests:
        lines.append(group_row("two-stage, rest pose", rests, []))
    lines += _baseline_rows(out)
    lines.append(_paper_row("two_stage"))

    lines += [
        "\n### Per seed\n",
        "| seed | per-episode score | coverage left / right / total | balance | union score "
        "| union parts left / right / total | parts never touched | rest-pose per-episode score "
        "| training score |\n|---|---|---|---|---|---|---|---|---|",
    ]
    for run, e, train in zip(runs, finals, trains):
        rest = _load(run / "rest" / "eval.json")
        lines.append("| " + " | ".join([
            _seed(run),
            _own(e, "score"),
            " / ".join(_own(e, k, 1) for k in COVERAGE),
            _own(e, "balance", 1),
            _union_text(e),
            f"{e['coverage_left']} / {e['coverage_right']} / {e['coverage_total']}",
            _never(e),
            _own(rest, "score") if rest else "-",
            "-" if train is None else f"{train:.3f}",
        ]) + " |")  # fmt: skip

    curves = {_seed(r): curve(r) for r in runs}
    all_steps = sorted({s for c in curves.values() for s in c})
    stage = finals[0]["config"]["behavior"].get("fixed_pose_steps")
    lines += [
        "\n### Evaluation curve (per-episode score, random poses)\n",
        "| steps | mean over seeds | " + " | ".join(f"seed {s}" for s in curves) + " |",
        "|---|---|" + "---|" * len(curves),
    ]
    for step in all_steps:
        values = [c[step]["episode_score_mean"] if step in c else None for c in curves.values()]
        label = f"{step:,}" + (" (stage switch)" if step == stage else "")
        cells = ["-" if v is None else f"{v:.3f}" for v in values]
        lines.append(f"| {label} | {_ci(values)} | " + " | ".join(cells) + " |")
    picture = draw_curve(out, curves, stage)

    median = median_seed(runs)
    lines += [
        f"\nCurve: {picture}. Median seed by final per-episode score: "
        f"{_seed(median)} ({_load(median / 'eval' / 'eval.json')['episode_score_mean']:.3f}); "
        f"its body map is {median / 'eval' / 'self_touch_body_map.png'}; a video of one episode "
        "and its policy file:\n",
        "```bash",
        f"devlearn eval self_touch --checkpoint {median}/checkpoint_{steps}.pt --episodes 1 "
        f"--seed 0 --video {out}/median_seed_episode.mp4 --out {out}/median_seed_video",
        f"devlearn slim {median}/checkpoint_{steps}.pt --out {median}/policy.pt",
        "```",
    ]
    return "\n".join(lines)


def draw_curve(out: Path, curves: dict[str, dict[int, dict]], stage: int | None) -> Path:
    """OUT/eval_curve.png: per-episode score against steps, one line per seed; baselines and
    the stage switch as reference lines."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 4.2), constrained_layout=True)
    ax = fig.subplots()
    for seed, points in curves.items():
        ax.plot(
            list(points),
            [p["episode_score_mean"] for p in points.values()],
            marker="o",
            label=f"seed {seed}",
        )
    for policy, style in (("random", "--"), ("zero", ":")):
        e = _load(out / f"baseline_{policy}" / "eval.json")
        if e is not None:
            ax.axhline(e["episode_score_mean"], color="grey", ls=style, label=f"{policy} actions")
    if stage:
        ax.axvline(stage, color="black", lw=0.8, alpha=0.5, label="random poses from here")
    ax.set_xlabel("physics steps")
    episodes = next(iter(next(iter(curves.values())).values()))["protocol"]["episodes"]
    ax.set_ylabel(f"per-episode score ({episodes} random-pose episodes)")
    ax.set_ylim(bottom=0)
    ax.set_title("Self-touch, two-stage curriculum: evaluation per checkpoint")
    ax.legend(fontsize=8)
    path = out / "eval_curve.png"
    fig.savefig(path, dpi=110)
    return path


def ablation_tables(out: Path) -> str:
    arms: dict[str, list[Path]] = {}
    for run in sorted(out.glob("runs/curriculum=*,seed=*"), key=lambda r: int(_seed(r))):
        if (run / "eval" / "eval.json").exists():
            arms.setdefault(run.name.split(",")[0].split("=")[1], []).append(run)
    if not arms:
        raise SystemExit(f"no finished runs (runs/curriculum=ARM,seed=N/eval/eval.json) in {out}")
    lines = [HEADLINE]
    scores: dict[str, list[float]] = {}
    for arm, runs in arms.items():
        evals = [_load(r / "eval" / "eval.json") for r in runs]
        scores[arm] = [e["episode_score_mean"] for e in evals]
        steps = evals[0]["checkpoint_env_steps"]
        lines.append(
            group_row(f"{arm} ({steps:,} steps)", evals, [training_score(r) for r in runs])
        )
        rests = [e for r in runs if (e := _load(r / "rest" / "eval.json")) is not None]
        if rests:
            lines.append(group_row(f"{arm}, rest pose", rests, []))
    lines += _baseline_rows(out)
    lines += [_paper_row(arm) for arm in ("fixed_only", "random_only", "two_stage")]
    lines.append("\nDifferences of per-episode score (Welch 95% interval over seeds):\n")
    for a, b in itertools.combinations(arms, 2):
        lines.append(f"- {a} - {b}: {_welch(scores[a], scores[b], '.3f', p_value=True)}")
    order = sorted(arms, key=lambda a: -statistics.mean(scores[a]))
    lines.append(
        f"\nOrder by mean per-episode score: {' > '.join(order)} "
        "(the paper's, by its union score: two_stage > fixed_only > random_only)."
    )
    return "\n".join(lines)


def _welch(a: list[float], b: list[float], fmt: str = ".3g", p_value: bool = False) -> str:
    """``mean(a) - mean(b) [95% Welch interval]`` (and its p-value), numbers as ``fmt``; the
    difference alone below 2 values each."""
    from scipy import stats

    diff = statistics.mean(a) - statistics.mean(b)
    if min(len(a), len(b)) < 2:
        return f"{diff:+{fmt}}"
    test = stats.ttest_ind(a, b, equal_var=False)
    ci = test.confidence_interval()
    text = f"{diff:+{fmt}} [{ci.low:+{fmt}}, {ci.high:+{fmt}}]"
    return f"{text} (p = {test.pvalue:.3f})" if p_value else text


PILOT_DIFFERENCES = (
    ("per-episode score", lambda e: e["episode_score_mean"]),
    ("balance (per episode)", lambda e: e["episode_balance_mean"]),
    ("|hand preference|", lambda e: abs(decompose(e["episode_parts"])["preference"])),
    ("touches / min", lambda e: e["likeness"]["touches_per_minute"]),
    ("distinct regions / min", lambda e: e["likeness"]["distinct_regions_per_minute"]),
    ("time a hand touches the body", lambda e: e["likeness"]["contact_time_share"]),
)


def pilot_tables(out: Path) -> str:
    pilots: dict[str, list[Path]] = {}
    for pilot in ("control", "balance", "repeats", "rate"):
        runs = sorted(out.glob(f"{pilot}/seed=*"), key=lambda r: int(_seed(r)))
        runs = [r for r in runs if (r / "eval" / "eval.json").exists()]
        if runs:
            pilots[pilot] = runs
    if not pilots:
        raise SystemExit(f"no finished runs (PILOT/seed=N/eval/eval.json) in {out}")
    evals = {p: [_load(r / "eval" / "eval.json") for r in runs] for p, runs in pilots.items()}
    baselines = {
        f"{policy} actions{label}": e
        for suffix, label in (("", ""), ("_k10", ", held 10 steps (rate's)"))
        for policy in ("zero", "random")
        if (e := _load(out / f"baseline_{policy}{suffix}" / "eval.json")) is not None
    }
    lines = [HEADLINE]
    for pilot, runs in pilots.items():
        seeds = ",".join(_seed(r) for r in runs)
        label = f"{pilot} (seeds {seeds}, {evals[pilot][0]['checkpoint_env_steps']:,} steps)"
        lines.append(group_row(label, evals[pilot], [training_score(r) for r in runs]))
    lines += _baseline_rows(out)

    lines.append("\nThe balance's sources (balance.py; mean over seeds, preference as |L - R|):\n")
    cols = ("balance", "preference", "without_preference", "bonus_paid")
    lines.append("| | " + " | ".join(c.replace("_", " ") for c in cols) + " |")
    lines.append("|---" * (len(cols) + 1) + "|")
    for name, group in [*evals.items(), *((k, [v]) for k, v in baselines.items())]:
        parts = [decompose(e["episode_parts"]) for e in group]
        cells = [_ci([abs(d[c]) for d in parts], 2) for c in cols]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")

    lines.append("\nLikeness (mean and 95% t-interval over seeds):\n")
    head = [label for _, label in MEASURES] + [f"share of touches: {a}" for a in AREAS]
    lines.append("| | " + " | ".join(head) + " |")
    lines.append("|---" * (len(head) + 1) + "|")
    for name, group in [*evals.items(), *((k, [v]) for k, v in baselines.items())]:
        like = [e["likeness"] for e in group]
        cells = [_ci([r[key] for r in like if r[key] is not None]) for key, _ in MEASURES]
        cells += [
            _ci([r["touch_share_by_area"].get(a, 0.0) for r in like if r["touches"]]) for a in AREAS
        ]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")

    lines.append("\nEach pilot minus the control (Welch 95% interval over seeds):\n")
    lines.append("| | " + " | ".join(name for name, _ in PILOT_DIFFERENCES) + " |")
    lines.append("|---" * (len(PILOT_DIFFERENCES) + 1) + "|")
    for pilot in (p for p in evals if p != "control" and "control" in evals):
        cells = [
            _welch([f(e) for e in evals[pilot]], [f(e) for e in evals["control"]])
            for _, f in PILOT_DIFFERENCES
        ]
        lines.append(f"| {pilot} - control | " + " | ".join(cells) + " |")
    return "\n".join(lines)


TABLES = {"curriculum": curriculum_tables, "ablation": ablation_tables, "pilots": pilot_tables}

if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in TABLES:
        raise SystemExit(f"usage: python results/self_touch/table.py {'|'.join(TABLES)} OUT")
    print(TABLES[sys.argv[1]](Path(sys.argv[2])))
