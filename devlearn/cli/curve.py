"""``devlearn curve DIR [DIR ...]``: plot learning curves.

Run folders (``metrics.jsonl``, from ``devlearn run``) give one line each: training metrics per
iteration. Evaluation folders (``eval.json``, from ``devlearn eval --out``) of checkpoints of one
run give together one line per start (random starts and rest starts, as each eval.json records,
are kept apart): each evaluation is a point at its checkpoint's environment steps; ``--vs`` adds
another line (say, the evaluations of a second run, to compare the two). Evaluations show the
behaviour's headline and its per-episode mean (with its 95% interval) unless ``--metric`` says.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from devlearn.api.errors import UsageError
from devlearn.api.json_files import read_json, read_json_lines, read_json_object

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry

SMOOTH_MAX = 100_000
"""Largest ``--smooth`` window (iterations)."""


def is_step(value: Any) -> bool:
    """Whether ``value`` is an environment step count a run can log: a whole number from 0
    to the longest run (:data:`~devlearn.config.checks.STEPS_MAX`)."""
    from devlearn.config.checks import STEPS_MAX

    number = isinstance(value, int | float) and not isinstance(value, bool)
    return number and math.isfinite(value) and value == int(value) and 0 <= value <= STEPS_MAX


def figures(row: dict) -> dict[str, float]:
    """The numbers of a metrics row or an evaluation, by key: strings, lists, tables and
    booleans are nothing to draw."""
    return {k: v for k, v in row.items() if isinstance(v, int | float) and not isinstance(v, bool)}


def read_metrics(run_dir: Path) -> list[dict]:
    """Return the rows of ``run_dir/metrics.jsonl`` (one dict per iteration, its numbers).

    A line that is no row (garbled, not a JSON object, without a ``step`` a run can log) is
    skipped with a warning naming it; a last line cut short by a kill is skipped quietly.

    Raises:
        UsageError: No metrics.jsonl, an unreadable one, or none of its lines a row.
    """
    path = run_dir / "metrics.jsonl"
    if not path.exists():
        raise UsageError(f"{path} does not exist; pass a folder made by `devlearn run`")
    found, bad = read_json_lines(path, keep=lambda row: is_step(row.get("step")))
    rows = [figures(row) for row in found]
    if bad:
        shown = ", ".join(map(str, bad[:5])) + (", ..." if len(bad) > 5 else "")
        print(
            f"devlearn: warning: {path}: skipped {len(bad)} line(s) ({shown}): not a metrics "
            "row (a JSON object with a whole 'step' from 0)",
            file=sys.stderr,
        )
    if not rows:
        raise UsageError(f"{path} holds no complete rows yet")
    return rows


def read_evaluations(eval_dirs: list[Path]) -> list[dict]:
    """Each folder's ``eval.json`` as a ``step``-keyed row (``checkpoint_env_steps``), by step."""
    rows = []
    for eval_dir in eval_dirs:
        path = eval_dir / "eval.json"
        if not path.exists():
            raise UsageError(
                f"{eval_dir} holds neither metrics.jsonl (a run) nor eval.json (an evaluation)"
            )
        summary = read_json_object(path, "an evaluation")
        if "checkpoint_env_steps" not in summary:
            raise UsageError(
                f"{path} has no checkpoint_env_steps (older evaluations lack it): "
                "evaluate the checkpoint again"
            )
        if not is_step(summary["checkpoint_env_steps"]):
            raise UsageError(
                f"{path}: checkpoint_env_steps {summary['checkpoint_env_steps']!r} is not a step "
                "count (a whole number from 0)"
            )
        numbers = figures(summary)
        protocol = summary.get("protocol")
        protocol = protocol if isinstance(protocol, dict) else {}
        rows.append(
            {
                **numbers,
                "step": summary["checkpoint_env_steps"],
                "_start": start_label(protocol),
                "_headline": protocol.get("headline") or "",
            }
        )
    return sorted(rows, key=lambda row: row["step"])


def start_label(protocol: dict) -> str:
    """Where an evaluation's episodes started, from its protocol: ``rest start`` (``--start
    rest``), ``random starts`` (the stage's seeded random poses) or ``stage starts``."""
    if protocol.get("start") == "rest":
        return "rest start"
    stage = protocol.get("stage")
    if not isinstance(stage, dict):
        stage = {}
    return "random starts" if stage.get("random_pose", True) else "stage starts"


BOOKKEEPING = {"step", "checkpoint_env_steps", "episodes", "steps", "settle_steps", "training_seed"}
"""Numbers an eval.json records about the protocol or the run, not results: never a default."""


def default_eval_metrics(rows: list[dict]) -> list[str]:
    """What ``devlearn curve EVAL_DIRS`` draws unless ``--metric`` says: each headline (the
    behaviour's, recorded in the protocol) and its per-episode mean; without a recorded
    headline every result number except spreads and intervals (``*_std``, ``*_ci_low``...)."""
    present = {k for r in rows for k in r if not k.startswith("_")}
    keys = []
    for name in dict.fromkeys(r["_headline"] for r in rows if r.get("_headline")):
        keys += [k for k in (name, f"episode_{name}_mean") if k in present and k not in keys]
    if keys:
        return keys
    spread = ("_std", "_ci_low", "_ci_high", "_sem")
    return sorted(k for k in present - BOOKKEEPING if not k.endswith(spread))


def _by_start(lines: list[tuple[Path, list[dict]]]) -> list[tuple[str, list[dict]]]:
    """Each line of evaluations split by where their episodes started (random and rest starts
    of the same checkpoints are different measurements), labelled with the start."""
    split = []
    for label, rows in lines:
        for start in dict.fromkeys(r["_start"] for r in rows):
            split.append((f"{label}, {start}", [r for r in rows if r["_start"] == start]))
    return split


HEALTH_KEYS = ("learning_rate", "loss/surrogate", "loss/value")
"""Learner figures drawn with ``--health`` beside every ``health/*`` key."""


def is_counter(key: str) -> bool:
    """Whether a metrics key counts things (``metrics/training_score_episodes``): not drawn by
    default, it only grows."""
    return key.rsplit("/", 1)[-1].endswith("episodes")


def run_headline(run_dir: Path, registry: PluginRegistry | None) -> str | None:
    """The metrics key of the run's behaviour's headline, the per-episode mean as evaluation
    measures it (``metrics/episode_score_mean``,
    :func:`~devlearn.training.runner_metrics.headline_key`), when its config.json names an
    installed behaviour that declares one."""
    from devlearn.training.runner_metrics import headline_key

    try:
        name = read_json(run_dir / "config.json")["behavior_name"]
        headline = registry.behavior(name).about.headline_metric if registry is not None else ""
    except (OSError, ValueError, KeyError, TypeError, UsageError):
        return None
    return headline_key(headline) if headline else None


def legacy_headline(key: str | None) -> str | None:
    """What a run logged before :func:`run_headline`'s key existed (``metrics/score`` for
    ``metrics/episode_score_mean``): the same per-episode mean under the behaviour's name."""
    if not key or not key.startswith("metrics/episode_") or not key.endswith("_mean"):
        return None
    return "metrics/" + key.removeprefix("metrics/episode_").removesuffix("_mean")


def default_run_metrics(every: set[str], headline: str | None, health: bool) -> list[str]:
    """What ``devlearn curve RUN`` draws: the headline, the reward, the behaviour's other
    metrics (no counters) and, with ``health``, the learner's health."""
    first = [k for k in (headline, "mean_reward") if k in every]
    if headline not in every and legacy_headline(headline) in every:  # a run from before
        first.insert(0, str(legacy_headline(headline)))
    rest = sorted(k for k in every if k.startswith("metrics/") and not is_counter(k))
    keys = first + [k for k in rest if k not in first]
    if health:
        keys += sorted(k for k in every if k.startswith("health/"))
        keys += [k for k in HEALTH_KEYS if k in every]
    return keys


def default_out(dirs: list[Path], evaluations: bool) -> Path:
    """Runs: the first run folder's ``learning_curve.png``. Evaluations: ``eval_curve.png`` in
    the folder that holds them all (the run folder for ``RUN/eval_*``), never inside one of the
    evaluation folders."""
    if not evaluations:
        return dirs[0] / "learning_curve.png"
    common = Path(os.path.commonpath([d.resolve() for d in dirs]))
    while (common / "eval.json").exists() and common.parent != common:
        common = common.parent
    return common / "eval_curve.png"


def _load(groups: list[list[Path]]) -> tuple[list[tuple[Path, list[dict]]], bool]:
    """(label, rows) per line, and whether these are evaluations; one kind of folder only.

    Runs: one line per folder. Evaluations: one line per group (the positional folders, then
    each ``--vs``), labelled by the folders' common parent.
    """
    dirs = [d for group in groups for d in group]
    evaluations = [d for d in dirs if not (d / "metrics.jsonl").exists()]
    if not evaluations:
        return [(run_dir, read_metrics(run_dir)) for run_dir in dirs], False
    if len(evaluations) < len(dirs):
        raise UsageError("give either run folders or evaluation folders, not both")
    if len(groups) == 1:
        return [(Path("evaluation"), read_evaluations(dirs))], True
    common = [Path(os.path.commonpath([d.resolve() for d in g])) for g in groups]
    return [(Path(os.path.relpath(c)), read_evaluations(g)) for c, g in zip(common, groups)], True


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Plot the chosen metrics (moving average) against steps and write a PNG."""
    from functools import partial

    import matplotlib

    from devlearn.files import check_out_file, write_atomically

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    chosen = picture_path(args.out) if args.out else None  # refused before any work
    if chosen is not None:
        check_out_file(chosen)  # a folder, a FIFO, a missing or unwritable folder
    runs: list[tuple[Any, list[dict]]]  # (run folder, rows), then (label, rows) by start
    runs, evaluations = _load([list(args.run_dirs), *(args.vs or [])])
    every = {k for _, rows in runs for r in rows for k in r if not k.startswith("_")}
    if evaluations:
        default = default_eval_metrics([r for _, rows in runs for r in rows])
        runs = _by_start(runs)
    else:
        headline = run_headline(Path(runs[0][0]), registry)
        default = default_run_metrics(every, headline, getattr(args, "health", False))
    keys = args.metric or default or ["mean_step_reward"]  # before any episode ended
    unknown = [k for k in keys if k not in every]
    if unknown or not keys:
        raise UsageError(f"no such metric(s) {unknown}; valid: {', '.join(sorted(every))}")
    if not 1 <= args.smooth <= SMOOTH_MAX:
        raise UsageError(f"--smooth must be from 1 to {SMOOTH_MAX}, got {args.smooth}")
    out = chosen or default_out(list(args.run_dirs), evaluations)
    check_out_file(out)  # the default beside the runs too, before the drawing
    # constrained layout places the title above the first panel, never over it
    fig, axes = plt.subplots(
        len(keys), 1, figsize=(7, 2.4 * len(keys)), squeeze=False, layout="constrained"
    )
    for ax, key in zip(axes[:, 0], keys):
        if len(runs) > 10:  # matplotlib's default cycle repeats after 10 colours
            ax.set_prop_cycle(color=[plt.get_cmap("tab20")(i) for i in range(20)])
        for run_dir, rows in runs:
            points = [(r["step"], r[key]) for r in rows if r.get(key) is not None]
            if not points:
                continue
            steps, values = (np.array(v, dtype=float) for v in zip(*points))
            if evaluations:
                line = ax.plot(steps, values, marker="o", lw=1.6, label=str(run_dir))[0]
                base = key.removesuffix("_mean")
                band = [
                    (r["step"], r.get(f"{base}_ci_low"), r.get(f"{base}_ci_high")) for r in rows
                ]
                band = [b for b in band if b[1] is not None and b[2] is not None]
                if key.endswith("_mean") and band:  # the per-episode 95% interval
                    x, low, high = (np.array(v, dtype=float) for v in zip(*band))
                    ax.fill_between(x, low, high, color=line.get_color(), alpha=0.15, lw=0)
                continue
            window = min(args.smooth, len(values))
            smooth = np.convolve(values, np.ones(window) / window, mode="valid")
            if len(runs) == 1:
                ax.plot(steps, values, color="0.8", lw=0.8)
            ax.plot(steps[window - 1 :], smooth, lw=1.6, label=Path(run_dir).name)
        ax.set_ylabel(key.split("/")[-1])
        ax.grid(alpha=0.3)
    if len(runs) > 1 or evaluations:
        # beside the plot, not over it: a sweep's many runs would hide the curves
        axes[0, 0].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    title = args.run_dirs[0].name if len(runs) == 1 else f"{len(runs)} runs"
    if evaluations:
        axes[-1, 0].set_xlabel("environment steps of the checkpoint")
        count = len(
            {(str(label).rsplit(", ", 1)[0], r["step"]) for label, rows in runs for r in rows}
        )
        starts = sorted({r["_start"] for _, rows in runs for r in rows})
        fig.suptitle(f"evaluations of {count} checkpoints ({' / '.join(starts)})")
    else:
        axes[-1, 0].set_xlabel("environment steps")
        fig.suptitle(f"{title}: mean over episodes ending in each iteration")
    try:  # the legend beside the axes included
        save = partial(fig.savefig, format=out.suffix[1:].lower(), dpi=110, bbox_inches="tight")
        write_atomically(out, save)
    except OSError as exc:
        raise UsageError(f"cannot write {out}: {exc.strerror or exc}") from None
    finally:
        plt.close(fig)
    print(out)
    return 0


def picture_path(out: str | Path) -> Path:
    """The file ``--out`` names, as matplotlib writes it: ``PATH.png`` for a name without a
    suffix (matplotlib adds it; the path printed is the one written).

    Raises:
        UsageError: A suffix matplotlib writes no picture for (the valid ones named).
    """
    from matplotlib.figure import Figure

    path = Path(out)
    formats = sorted(Figure().canvas.get_supported_filetypes())
    suffix = path.suffix.lower().removeprefix(".")
    if not suffix:
        return path.with_name(path.name + ".png")
    if suffix not in formats:
        raise UsageError(
            f"--out {out}: no picture format '{suffix}'; give a file ending in one of "
            f"{', '.join('.' + f for f in formats)}"
        )
    return path
