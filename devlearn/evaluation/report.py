"""``devlearn report``: evaluations grouped by variant, mean and 95% interval over seeds beside the
baselines and the paper's figures, written as a Markdown table (report.md) and a bar chart
(report.png)."""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from devlearn.api.errors import UsageError
from devlearn.api.json_files import read_json
from devlearn.api.stats import CONFIDENCE, mean_ci
from devlearn.config.checks import check_out_dir
from devlearn.files import check_replaceable, write_atomically, write_text_atomically

PaperResults = Callable[[str, dict[str, Any]], "tuple[str, dict[str, float]] | None"]
"""(behaviour name, a run's config) -> (column label, the paper's figures) or None: the named
behaviour's :meth:`devlearn.Behavior.paper_results`."""

ConfigLoader = Callable[[str, dict[str, Any]], dict[str, Any]]
"""(behaviour name, a run's saved config) -> that config as a run loads it (keys saved before a
rename upgraded, missing keys filled as the run was trained): in the CLI, the behaviour's
``from_dict`` then ``to_dict``. Configs of the same recipe then compare equal however old."""

REPORT_FILES = ("report.md", "report.png")
"""The files :func:`write_report` writes in its folder."""
BASELINES = ("zero", "random", "held_random")
"""Baseline policies (``devlearn eval BEHAVIOR --policy ...``) shown beside every variant."""
NOT_VARIANT = frozenset(
    {
        "seed",
        "out_dir",
        "device",
        "workers",
        "torch_threads",
        "update_threads",
        "save_interval",
        "preset",
        "start_from",
        "behavior.detector_file",
    }
)
"""Config keys that never make a variant: the seed (pooled) and where or how a run ran (a
preset's name and a ``--from`` checkpoint are recorded only: the values they set do count)."""
NOT_METRIC = frozenset(
    {
        "config",
        "protocol",
        "paper",
        "part_touch_steps",
        "detector_agreement",
        "detector_visibility",
        "episodes",
        "steps",
        "parts",
        "settle_steps",
        "checkpoint_env_steps",
        "training_seed",
        "execution",
    }
)
"""Eval-JSON keys that are not metrics (settings, references, bookkeeping)."""
LEARNER = "learner"
"""The variant key of who trained a policy: an eval JSON's ``learner`` (a scripted policy's,
e.g. ``sb3_ppo``), :data:`DEVLEARN_LEARNER` for a devlearn checkpoint."""
DEVLEARN_LEARNER = "devlearn_ppo"
"""The learner of a devlearn checkpoint (its eval JSON names none)."""
EVALUATED_AGE = "eval.age_months"
"""The variant key of the body's age an evaluation ran at (``devlearn eval --set
infant.age_months=A``; null: the default body): a policy evaluated at several ages is a column
per age, and so is a baseline."""
SINGLE_VARIANT = "trained"
"""Column name of the checkpoints when their configs differ only in seed (one variant)."""


def flatten(data: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """A nested dict's leaves by dotted key (``ppo.learning_rate``)."""
    out: dict[str, Any] = {}
    for key, value in data.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            out.update(flatten(value, name + "."))
        else:
            out[name] = value
    return out


def _metrics(summary: dict[str, Any]) -> dict[str, float]:
    """Numeric metrics of one eval JSON, dotted keys; per-episode spreads left out."""
    out = {}
    for key, value in flatten(summary).items():
        parts = key.split(".")
        if parts[0] in NOT_METRIC or key.endswith(("_std", "_ci_low", "_ci_high")):
            continue
        if parts[0] == "criteria" and "visibility" in parts:
            continue  # per-pair values of the secondary criteria: their averages suffice
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            out[key] = float(value)
    return out


def headline_of(summary: dict, behavior_headline: str = "") -> tuple[str, float, tuple] | None:
    """``(key, value, (low, high) or ())``: the behaviour's headline as a reader wants it, the
    per-episode mean with its 95% interval where the evaluator reports one (self-touch's
    ``episode_score_mean``), else the headline's own figure."""
    names = [(summary.get("protocol") or {}).get("headline"), behavior_headline]
    keys = [k for n in names if n for k in (f"episode_{n}_mean", f"{n}_mean", f"mean_{n}", n)]
    for key in keys:
        value = summary.get(key)
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            base = key.removesuffix("_mean")
            low, high = summary.get(f"{base}_ci_low"), summary.get(f"{base}_ci_high")
            return key, float(value), (low, high) if low is not None and high is not None else ()
    return None


def _eval_files(path: Path) -> list[Path]:
    if not path.exists():
        raise UsageError(
            f"{path} does not exist; give evaluation folders (with eval.json) "
            "or run folders that contain them"
        )
    if path.is_file():
        return [path] if path.name == "eval.json" else []
    if (path / "eval.json").is_file():
        return [path / "eval.json"]
    return sorted(path.rglob("eval.json"))


def _read(file: Path) -> dict[str, Any] | None:
    """An evaluation's summary, or None for one made before the protocol was recorded.

    Raises:
        UsageError: Unreadable (:func:`~devlearn.api.json_files.read_json`).
    """
    data = read_json(file)
    return data if isinstance(data, dict) and "protocol" in data else None


def collect(
    paths: Sequence[str | Path], skipped: list[str] | None = None
) -> tuple[list[tuple[Path, dict]], list[str]]:
    """The evaluations under ``paths`` plus baselines of the same behaviour found beside them
    (in the folders next to a path or next to its parent). An unreadable evaluation the paths
    name is refused; an unreadable one found beside them is skipped, with a note (and its
    reason appended to ``skipped``, for a warning).

    Returns:
        ``([(eval.json path, summary), ...], notes)``.
    Raises:
        UsageError: No paths, a path without evaluations or with an unreadable one, or
            evaluations of several behaviours.
    """
    if not paths:
        raise UsageError("report needs at least one evaluation or run folder")
    found: dict[Path, dict] = {}
    notes: list[str] = []
    old: list[Path] = []
    unreadable: dict[Path, str] = {}
    for path in map(Path, paths):
        files = _eval_files(path)
        if not files:
            raise UsageError(f"{path} holds no eval.json (run `devlearn eval` first)")
        for file in files:
            data = _read(file)
            if data is None:
                old.append(file)
            else:
                found[file.resolve()] = data
        if not found:
            continue
        near = path.resolve().parent
        behaviors = {d.get("behavior") for d in found.values()}
        for file in sorted([*near.glob("*/eval.json"), *near.parent.glob("*/eval.json")]):
            if file.resolve() in found or file.resolve() in unreadable:
                continue
            try:  # the guarded reader: a FIFO named eval.json is refused, never waited on
                data = _read(file)  # a baseline beside it, of the same behaviour
            except UsageError as err:  # not given: a stray file is no reason to stop
                unreadable[file.resolve()] = str(err)
                continue
            if data is not None and data.get("policy") in BASELINES:
                if data.get("behavior") in behaviors:
                    found.setdefault(file.resolve(), data)
    for reason in unreadable.values():
        notes.append(f"skipped an unreadable evaluation found beside them: {reason}")
        if skipped is not None:
            skipped.append(reason)
    if old:
        notes.append(
            f"skipped {len(old)} evaluation(s) made before the protocol was recorded "
            f"(e.g. {old[0]}); re-evaluate them with `devlearn eval`"
        )
    if not found:
        where = ", ".join(map(str, paths))
        raise UsageError(f"no evaluation with a recorded protocol under {where}")
    names = sorted({d.get("behavior", "?") for d in found.values()})
    if len(names) > 1:
        raise UsageError(
            f"evaluations of different behaviours mixed ({', '.join(names)}); "
            "report one behaviour at a time"
        )
    return sorted(found.items()), notes


def group(
    evaluations: list[tuple[Path, dict]], as_loaded: ConfigLoader | None = None
) -> tuple[dict[str, list], list[str]]:
    """Group checkpoint evaluations by variant (differing config keys, and ``learner``: who
    trained the policy), baselines by policy.

    A run evaluated at several checkpoints counts once, with its latest checkpoint. With
    ``as_loaded``, configs are compared as runs load them (a config saved with
    ``behavior.weight_balance`` and one with ``behavior.rewards.balance.weight`` of the same
    value are one variant); without it, as saved.

    Returns:
        ``({column name: [(path, summary), ...]}, notes)``; variants first, then baselines.
    """
    notes: list[str] = []
    runs = [(p, d) for p, d in evaluations if d.get("policy", "checkpoint") == "checkpoint"]
    saved = [d.get("config") or {} for _, d in runs]
    if as_loaded is not None:
        saved = [as_loaded(d.get("behavior", "?"), c) for (_, d), c in zip(runs, saved)]
    configs = [
        {k: json.dumps(v) for k, v in flatten(c).items() if k not in NOT_VARIANT} for c in saved
    ]
    for config, (_, data) in zip(configs, runs):
        # another learner, same config: a variant; one policy at several ages: a column per age
        config[LEARNER] = json.dumps(data.get(LEARNER, DEVLEARN_LEARNER))
        config[EVALUATED_AGE] = json.dumps(data.get("age_months"))
    keys = sorted({k for c in configs for k in c if len({x.get(k) for x in configs}) > 1})
    columns: dict[str, dict] = {}
    for (path, data), config in zip(runs, configs):
        name = (
            ", ".join(f"{k}={json.loads(config[k]) if k in config else '-'}" for k in keys)
            or SINGLE_VARIANT
        )
        seed = data.get("training_seed")
        seeds = columns.setdefault(name, {})
        kept = seeds.get(seed)
        if kept is not None:
            later = data.get("checkpoint_env_steps", 0) > kept[1].get("checkpoint_env_steps", 0)
            notes.append(
                f"seed {seed} of '{name}' evaluated more than once: kept "
                f"{(path if later else kept[0]).parent.name} (the later checkpoint)"
            )
            if not later:
                continue
        seeds[seed] = (path, data)
    out = {name: list(seeds.values()) for name, seeds in columns.items()}
    for policy in BASELINES:
        chosen = [(p, d) for p, d in evaluations if d.get("policy") == policy]
        ages = list(dict.fromkeys(d.get("age_months") for _, d in chosen))
        for age in sorted(ages, key=lambda a: -1.0 if a is None else a):
            name = f"{policy} baseline" if len(ages) == 1 else f"{policy} ({_body(age)}) baseline"
            out[name] = [(p, d) for p, d in chosen if d.get("age_months") == age]
    return out, notes


def _body(age: float | None) -> str:
    return "default body" if age is None else f"{age:g} months"


def paper_columns(
    columns: dict[str, list], variants: list[str], paper_results: PaperResults | None
) -> dict[str, dict[str, float]]:
    """The paper's figures for the variants: ``{column label: {metric: value}}``, one column
    per label (variants that share the paper's figures share its column)."""
    out: dict[str, dict[str, float]] = {}
    if paper_results is None:
        return out
    for c in variants:
        data = columns[c][0][1]
        found = paper_results(data.get("behavior", "?"), data.get("config") or {})
        if found is not None:
            out.setdefault(found[0], {k: float(v) for k, v in found[1].items()})
    return out


def write_report(
    paths: Sequence[str | Path],
    out_dir: str | Path,
    paper_results: PaperResults | None = None,
    as_loaded: ConfigLoader | None = None,
    skipped: list[str] | None = None,
    behavior_headline: Callable[[str], str] | None = None,
) -> dict[str, Any]:
    """Write ``out_dir/report.md`` (table) and ``out_dir/report.png`` (bars with error bars).

    Args:
        paths: Evaluation folders (with eval.json) or run folders containing them; zero and
            random baseline evaluations among them or in folders beside them are added.
        out_dir: Folder to write into (created).
        paper_results: Where the paper's figures for each variant come from (in the CLI, the
            behaviour's :meth:`devlearn.Behavior.paper_results`): columns after the baselines.
        as_loaded: How a saved config loads (:data:`ConfigLoader`; in the CLI, through the
            behaviour's config class), so that variants are told apart by what their runs
            trained with, not by how old their config files are; None: as saved.
        skipped: Receives why each evaluation found beside ``paths`` was skipped (an
            unreadable eval.json that was not given: the report is made without it).
        behavior_headline: The headline metric of a behaviour by name (in the CLI, the
            behaviour's :attr:`~devlearn.Behavior.headline_metric`), for evaluations whose
            protocol names a criterion rather than a metric (hand regard's ``detector``): the
            first row and the first panel.
    Returns:
        ``{"behavior", "metrics": [...], "columns": {name: {"kind", "seeds", "paths"}},
        "table": {metric: {column: {"n", "mean", "std", "ci_low", "ci_high", "values"}}},
        "notes": [...]}``; intervals are 95% Student-t over seeds (over evaluations for the
        baselines), None for a single seed; kinds are ``variant``, ``baseline``, ``paper``.
    Raises:
        UsageError: An empty or missing folder, mixed behaviours, no checkpoint evaluation; an
            ``out_dir`` where the report cannot be written (checked first: a file, a report
            file that is a device or FIFO, no permission).
    """
    out = Path(out_dir)
    check_out_dir(out)
    for name in REPORT_FILES:
        check_replaceable(out / name)
    evaluations, notes = collect(paths, skipped)
    columns, more = group(evaluations, as_loaded)
    notes += more
    variants = [c for c in columns if not c.endswith(" baseline")]
    if not variants:
        raise UsageError("only baseline evaluations given; add a checkpoint's evaluation")
    behavior = evaluations[0][1].get("behavior", "?")
    per_eval = {c: [_metrics(d) for _, d in columns[c]] for c in columns}
    names = [
        k for k in per_eval[variants[0]][0] if all(k in m for c in variants for m in per_eval[c])
    ]
    # the behaviour's headline first, as a reader wants it: the per-episode mean where the
    # evaluator reports one (self-touch's episode_score_mean, not the union score)
    own = behavior_headline(behavior) if behavior_headline is not None else ""
    found = headline_of(evaluations[0][1], own)
    headline = found[0] if found else None
    if headline in names:
        names.remove(headline)
        names.insert(0, headline)
    table: dict[str, dict[str, Any]] = {}
    for metric in names:
        table[metric] = {}
        for c in columns:
            values = [m[metric] for m in per_eval[c] if metric in m]
            table[metric][c] = {**mean_ci(values), "values": values}
    papers = paper_columns(columns, variants, paper_results)
    for label, figures in papers.items():
        for metric in names:
            values = [figures[metric]] if metric in figures else []
            table[metric][label] = {**mean_ci(values), "values": values}
    info = {
        c: {
            "kind": "variant" if c in variants else "baseline",
            "seeds": [d.get("training_seed") for _, d in columns[c]],
            "paths": [shown(p.parent) for p, _ in columns[c]],
        }
        for c in columns
    }
    info.update({label: {"kind": "paper", "seeds": [], "paths": []} for label in papers})
    for c in variants:
        if len(columns[c]) == 1:
            notes.append(
                f"'{c}' has a single seed ({info[c]['seeds'][0]}): no interval over "
                "seeds; its eval.json holds the per-episode interval"
            )
    protocols = {
        json.dumps(
            {k: d["protocol"].get(k) for k in ("episodes", "settle_steps", "criteria")},
            sort_keys=True,
        )
        for _, d in evaluations
    }
    if len(protocols) > 1:
        notes.append(
            "the evaluations used different protocols (episodes, settle steps or "
            "criteria): compare with care"
        )
    result = {
        "behavior": behavior,
        "metrics": names,
        "columns": info,
        "table": table,
        "notes": notes,
    }
    try:
        out.mkdir(parents=True, exist_ok=True)
        write_text_atomically(out / "report.md", markdown(result, evaluations))
        draw_report(result, out / "report.png")
    except OSError as exc:
        raise UsageError(f"cannot write the report to {out}: {exc.strerror or exc}") from None
    return result


# --- report.md ------------------------------------------------------------------------------
def shown(path: Path) -> str:
    """``path`` relative to the working directory when inside it (reports get committed)."""
    try:
        return str(path.relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)


def cell(stat: dict[str, Any]) -> str:
    """``mean [low, high]``, the mean alone without an interval, ``-`` without a value."""
    if stat["mean"] is None:
        return "-"
    if stat["ci_low"] is None:
        return f"{stat['mean']:.3g}"
    return f"{stat['mean']:.3g} [{stat['ci_low']:.3g}, {stat['ci_high']:.3g}]"


def column_title(name: str, info: dict[str, Any]) -> str:
    """A column's heading: its name and, for our runs and baselines, how many there are."""
    return name if info["kind"] == "paper" else f"{name} (n={len(info['seeds'])})"


def _runs(info: dict[str, Any]) -> str:
    """``seeds [1, 2, 3]`` for trained runs; baselines have no training seed: their count."""
    seeds = [s for s in info["seeds"] if s is not None]
    if not seeds:
        count = len(info["seeds"])
        return f"{count} evaluation{'s' if count != 1 else ''} of an untrained policy (no seed)"
    return f"seeds {seeds}"


def markdown(result: dict[str, Any], evaluations: list[tuple[Path, dict]]) -> str:
    cols = list(result["columns"])
    protocol = evaluations[0][1]["protocol"]
    lines = [
        f"# {result['behavior']}: evaluation report",
        "",
        f"Mean and {CONFIDENCE:.0%} t-interval over seeds (baselines: over their "
        f"evaluations). Protocol: {protocol.get('episodes')} episodes, eval seed "
        f"{protocol.get('seed')}, settle {protocol.get('settle_steps')} steps, headline "
        f"`{result['metrics'][0] if result['metrics'] else protocol.get('headline')}` "
        "(first row).",
        "",
    ]
    header = ["metric"] + [column_title(c, result["columns"][c]) for c in cols]
    lines += ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for metric, row in result["table"].items():
        lines.append("| " + " | ".join([f"`{metric}`"] + [cell(row[c]) for c in cols]) + " |")
    lines += ["", "Columns:"]
    for c, info in result["columns"].items():
        if info["kind"] == "paper":
            lines.append(f"- **{c}**: the paper's published figures (- where it gives none)")
        else:
            lines.append(f"- **{c}**: {_runs(info)} from {', '.join(info['paths'])}")
    if result["notes"]:
        lines += ["", "Notes:"] + [f"- {n}" for n in result["notes"]]
    return "\n".join(lines) + "\n"


# --- report.png -----------------------------------------------------------------------------
MAX_PANELS = 4
"""Metrics drawn (the headline first, in the report's order)."""


def draw_report(result: dict[str, Any], path: Path) -> Path:
    """Draw ``write_report``'s table as bars (deterministic: no timestamps in the PNG).

    Args:
        result: What :func:`write_report` returns.
        path: PNG to write.
    Returns:
        ``path``.
    """
    from matplotlib.figure import Figure  # no pyplot: no global backend state

    metrics = result["metrics"][:MAX_PANELS]
    columns = list(result["columns"])
    fig = Figure(figsize=(3.2 * max(len(metrics), 1), 3.6), constrained_layout=True)
    axes = np.atleast_1d(fig.subplots(1, max(len(metrics), 1)))
    colours = [f"C{i}" for i in range(len(columns))]
    kinds = {c: info["kind"] for c, info in result["columns"].items()}
    for ax, metric in zip(axes, metrics):
        row = result["table"][metric]
        means = [row[c]["mean"] if row[c]["mean"] is not None else np.nan for c in columns]
        low = [
            m - row[c]["ci_low"] if row[c]["ci_low"] is not None else 0.0
            for m, c in zip(means, columns)
        ]
        high = [
            row[c]["ci_high"] - m if row[c]["ci_high"] is not None else 0.0
            for m, c in zip(means, columns)
        ]
        x = np.arange(len(columns))
        ax.bar(x, means, color=colours)
        # an interval only where there is one (several runs): a single run's bar has no caps
        spread = [i for i, c in enumerate(columns) if row[c]["ci_low"] is not None]
        if spread:
            ax.errorbar(
                x[spread],
                np.array(means)[spread],
                yerr=[np.array(low)[spread], np.array(high)[spread]],
                fmt="none",
                ecolor="k",
                capsize=4,
            )
        for i, c in enumerate(columns):  # the seeds themselves
            values = row[c]["values"]
            ax.plot(np.full(len(values), i), values, "k.", markersize=4)
        ticks = [c if kinds[c] == "paper" else f"{c}\n(n={row[c]['n']})" for c in columns]
        ax.set_xticks(x, ticks, fontsize=7, rotation=20)
        ax.set_title(metric, fontsize=9)
    fig.suptitle(f"{result['behavior']}: mean and 95% interval over seeds", fontsize=10)
    write_atomically(
        path, lambda f: fig.savefig(f, format="png", dpi=110, metadata={"Software": None})
    )
    return path
