"""The tables of a published experiment: per protocol, every arm's headline over seeds beside
the baselines and the references.

:func:`experiment_table` reads a publication (``devlearn experiment publish``'s DEST) into one
dict (``devlearn experiment table --json``); :func:`markdown` writes it for people. Figures
other than the headline (``--metric likeness.touches_per_minute``: any number in eval.json, by
its dotted key) get a table of their own per protocol.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from devlearn.api.errors import UsageError
from devlearn.api.stats import mean_ci
from devlearn.experiment.plan import baseline_name
from devlearn.experiment.publish import LEARNING_FILE, seed_folder
from devlearn.experiment.runner import EXPERIMENT_COPY, EXPERIMENT_INFO
from devlearn.experiment.spec import ExperimentSpec, Protocol, read_experiment
from devlearn.sweep.job import read_json


def _headline(summary: dict[str, Any] | None, behavior_headline: str) -> tuple | None:
    from devlearn.evaluation.report import headline_of

    return headline_of(summary, behavior_headline) if summary else None


def metric_value(summary: dict[str, Any] | None, key: str) -> float | None:
    """The number at dotted ``key`` of an eval.json (``likeness.touch_share_by_area.face``), or
    None where the evaluation has no such number."""
    value: Any = summary
    for part in key.split("."):
        if not isinstance(value, dict) or part not in value:
            return None
        value = value[part]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value)


def _metric_rows(
    dest: Path, spec: ExperimentSpec, protocol: Protocol, metrics: list[str]
) -> dict[str, Any]:
    """Each arm's ``metrics`` under ``protocol`` (mean and 95% t-interval over the seeds that
    report it, every seed's value) and each baseline's (its one evaluation)."""
    arms = []
    for arm in spec.arms:
        folders = {str(seed): dest / arm.name / seed_folder(seed) for seed in spec.seeds}
        summaries = {s: read_json(f / protocol.folder / "eval.json") for s, f in folders.items()}
        figures: dict[str, dict[str, Any]] = {}
        for key in metrics:
            values = {s: metric_value(v, key) for s, v in summaries.items() if v is not None}
            found = {s: v for s, v in values.items() if v is not None}
            figures[key] = {**mean_ci(list(found.values())), "seeds": found}
        arms.append({"arm": arm.name, "metrics": figures})
    baselines = []
    for policy in spec.baselines:
        summary = read_json(dest / baseline_name(policy) / protocol.folder / "eval.json")
        if summary is not None:
            evaluated = {key: metric_value(summary, key) for key in metrics}
            baselines.append({"baseline": policy, "metrics": evaluated})
    return {"keys": metrics, "arms": arms, "baselines": baselines}


def _arm_row(
    dest: Path, spec: ExperimentSpec, arm_name: str, protocol: Protocol, headline: str
) -> tuple[dict[str, Any], str | None]:
    """One arm's figures under ``protocol``, and the eval.json key of its headline."""
    values: dict[str, float] = {}
    seconds: dict[str, float] = {}
    key = None
    for seed in spec.seeds:
        run = dest / arm_name / seed_folder(seed)
        found = _headline(read_json(run / protocol.folder / "eval.json"), headline)
        if found is None:
            continue
        key = key or found[0]
        values[str(seed)] = found[1]
        learning = read_json(run / LEARNING_FILE) or {}
        if isinstance(learning.get("learn_s"), (int, float)):
            seconds[str(seed)] = float(learning["learn_s"])
    stats = mean_ci(list(values.values()))
    row = {
        "arm": arm_name,
        "learner": spec.arm(arm_name).learner,
        **stats,
        "seeds": values,
        "learn_s": {**mean_ci(list(seconds.values())), "seeds": seconds} if seconds else None,
    }
    return row, key


def experiment_table(dest: str | Path, metrics: list[str] | tuple[str, ...] = ()) -> dict[str, Any]:
    """The figures of publication ``dest``, per protocol: each arm's headline (the behaviour's,
    as ``devlearn eval``'s summary picks it: the per-episode mean where the evaluator reports
    one) as the mean and 95% t-interval over seeds (:func:`devlearn.api.stats.mean_ci`) with
    every seed's value and its seconds of learning where recorded; each baseline's headline
    under the same protocol (with its interval over episodes); the references of the protocol
    with their source. Each of ``metrics`` (an eval.json number by its dotted key) adds, per
    protocol, the same figures for that number (``"metrics"``: arms over seeds, baselines as
    evaluated).

    Raises:
        UsageError: ``dest`` is not a publication, or no evaluation in it has one of ``metrics``.
    """
    dest = Path(dest)
    info = read_json(dest / EXPERIMENT_INFO)
    if info is None or "published" not in info or not (dest / EXPERIMENT_COPY).is_file():
        raise UsageError(
            f"{dest} is not a published experiment (no {EXPERIMENT_INFO} and {EXPERIMENT_COPY} "
            "written by devlearn experiment publish)"
        )
    spec = read_experiment(dest / EXPERIMENT_COPY)
    headline = str(info.get("headline_metric") or "")
    tables = []
    for protocol in spec.protocols:
        arms, keys = [], []
        for arm in spec.arms:
            row, key = _arm_row(dest, spec, arm.name, protocol, headline)
            arms.append(row)
            keys.append(key)
        baselines = []
        for policy in spec.baselines:
            summary = read_json(dest / baseline_name(policy) / protocol.folder / "eval.json")
            found = _headline(summary, headline)
            if found is None:
                continue
            keys.append(found[0])
            low, high = found[2] if found[2] else (None, None)
            baselines.append(
                {"baseline": policy, "value": found[1], "ci_low": low, "ci_high": high}
            )
        references: list[dict[str, Any]] = [
            {
                "label": row.label,
                "value": row.value,
                "ci_low": row.low,
                "ci_high": row.high,
                "source": ref.source,
                "note": ref.note,
                "metrics": dict(row.metrics),
            }
            for ref in spec.references
            if ref.protocol == protocol.name
            for row in ref.rows
        ]
        found_keys = sorted({k for k in keys if k})
        table: dict[str, Any] = {
            "protocol": protocol.name,
            "description": protocol.describe(),
            "headline": found_keys[0] if len(found_keys) == 1 else found_keys or headline,
            "arms": arms,
            "baselines": baselines,
            "references": references,
        }
        if metrics:
            table["metrics"] = _metric_rows(dest, spec, protocol, list(metrics))
            table["metrics"]["references"] = [
                {"label": ref["label"], "source": _source(ref), "metrics": ref["metrics"]}
                for ref in references
                if any(key in ref["metrics"] for key in metrics)
            ]
        tables.append(table)
    for key in metrics:
        if not any(_has_metric(t["metrics"], key) for t in tables):
            raise UsageError(
                f"--metric {key}: no evaluation in {dest} has a number there (a dotted key of "
                "eval.json, e.g. likeness.touches_per_minute or episode_balance_mean)"
            )
    return {
        "experiment": spec.name,
        "behavior": spec.behavior,
        "description": spec.description,
        "headline_metric": headline,
        "commit": info.get("commit"),
        "commits": info.get("commits", []),
        "published": info.get("published"),
        "seeds": spec.seeds,
        "protocols": tables,
    }


def _has_metric(table: dict[str, Any], key: str) -> bool:
    return any(arm["metrics"][key]["n"] for arm in table["arms"]) or any(
        base["metrics"][key] is not None for base in table["baselines"]
    )


def figure(value: float | None) -> str:
    """A figure as the tables print it: 4 significant digits (``-`` for none)."""
    return "-" if value is None else f"{value:.4g}"


def _interval(stats: dict[str, Any]) -> str:
    if stats.get("mean") is None:
        return "-"
    if stats.get("ci_low") is None:
        return figure(stats["mean"])
    return f"{figure(stats['mean'])} [{figure(stats['ci_low'])}, {figure(stats['ci_high'])}]"


def _source(ref: dict[str, Any]) -> str:
    """A reference's source as the tables' footnotes name it (with its note)."""
    return str(ref["source"]) + (f" ({ref['note']})" if ref.get("note") else "")


def _metric_lines(metrics: dict[str, Any], sources: list[str]) -> list[str]:
    """The ``--metric`` figures of one protocol: a row per arm (mean [95% interval over the
    seeds], how many seeds), per baseline (its one evaluation) and per reference that gives
    one of them (its figure as the source gives it, numbered in ``sources``)."""
    keys = metrics["keys"]
    lines = ["| policy | seeds | " + " | ".join(keys) + " |", "|" + "---|" * (len(keys) + 2)]
    for arm in metrics["arms"]:
        seeds = max(arm["metrics"][key]["n"] for key in keys)
        cells = [_interval(arm["metrics"][key]) for key in keys]
        lines.append(f"| {arm['arm']} | {seeds} | " + " | ".join(cells) + " |")
    for base in metrics["baselines"]:
        cells = [figure(base["metrics"][key]) for key in keys]
        lines.append(f"| {base['baseline']} actions (baseline) | - | " + " | ".join(cells) + " |")
    for ref in metrics.get("references", []):
        if ref["source"] not in sources:
            sources.append(ref["source"])
        cells = [str(ref["metrics"].get(key, "-")) for key in keys]
        label = f"{ref['label']} (reference [{sources.index(ref['source']) + 1}])"
        lines.append(f"| {label} | - | " + " | ".join(cells) + " |")
    return [*lines, ""]


def markdown(table: dict[str, Any]) -> str:
    """The tables for people: one per protocol, then the sources of the references."""
    lines = [f"# {table['experiment']} ({table['behavior']})", ""]
    if table.get("description"):
        lines += [table["description"].strip(), ""]
    commits = table.get("commits") or [table.get("commit")]
    lines += [
        f"Code: commit {', '.join(str(c) for c in commits)}; published {table.get('published')}.",
        "",
    ]
    sources: list[str] = []
    for protocol in table["protocols"]:
        headline = protocol["headline"]
        key = headline if isinstance(headline, str) else " / ".join(headline)
        seconds = any(arm["learn_s"] for arm in protocol["arms"])
        lines += [f"## {protocol['protocol']}: {protocol['description']}", ""]
        header = ["policy", "seeds", f"{key}: mean [95% interval over seeds]", "per seed"]
        header += ["s of learning"] if seconds else []
        lines += ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
        for arm in protocol["arms"]:
            per_seed = ", ".join(f"{s}: {figure(v)}" for s, v in arm["seeds"].items())
            cells = [arm["arm"], str(arm["n"]), _interval(arm), per_seed or "-"]
            if seconds:
                cells.append(_interval(arm["learn_s"]) if arm["learn_s"] else "-")
            lines.append("| " + " | ".join(cells) + " |")
        for base in protocol["baselines"]:
            value = figure(base["value"])
            if base["ci_low"] is not None:
                value += f" [{figure(base['ci_low'])}, {figure(base['ci_high'])}] over episodes"
            cells = [f"{base['baseline']} actions (baseline)", "-", value, "-"]
            lines.append("| " + " | ".join(cells + (["-"] if seconds else [])) + " |")
        for ref in protocol["references"]:
            if ref["value"] is None:  # figures for --metric columns only
                continue
            source = _source(ref)
            if source not in sources:
                sources.append(source)
            number = sources.index(source) + 1
            cells = [f"{ref['label']} (reference [{number}])", "-"]
            cells += [_interval({"mean": ref["value"], **ref}), "-"]
            lines.append("| " + " | ".join(cells + (["-"] if seconds else [])) + " |")
        lines.append("")
        if protocol.get("metrics"):
            lines += _metric_lines(protocol["metrics"], sources)
    lines.append(
        "Arms: the headline's mean and 95% t-interval over seeds, each seed's value beside. "
        "Baselines: one evaluation under the same protocol, with its interval over episodes."
        + (
            " s of learning: devlearn's collect + update seconds summed over metrics.jsonl, "
            "SB3's seconds inside learn()."
            if any(arm["learn_s"] for p in table["protocols"] for arm in p["arms"])
            else ""
        )
        + (
            " Other figures (--metric): each eval.json number's mean and 95% t-interval over the "
            "seeds that report it; a baseline's one evaluation."
            if any(p.get("metrics") for p in table["protocols"])
            else ""
        )
    )
    if sources:
        lines += ["", "References:", ""]
        lines += [f"- [{i}] {source}" for i, source in enumerate(sources, 1)]
    return "\n".join(lines) + "\n"
