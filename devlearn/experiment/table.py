"""The tables of a published experiment: per protocol, every arm's headline over seeds beside
the baselines and the references.

:func:`experiment_table` reads a publication (``devlearn experiment publish``'s DEST) into one
dict (``devlearn experiment table --json``); :func:`markdown` writes it for people. Figures
other than the headline (``--metric likeness.touches_per_minute``: any number in eval.json, by
its dotted key) get a table of their own per protocol.

Several publications make one table (``devlearn experiment table DEST DEST2``): an arm of the
same name pools its seeds across them (seeds 1-5 of one experiment, 6-10 of a later one), when
both trained it alike (behaviour, budget, the arm's settings) and evaluated it under a protocol
of the same name and definition; ``--versus ARM`` adds each arm's paired difference from ARM
over the seeds both have.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from devlearn.api.errors import UsageError
from devlearn.api.stats import mean_ci
from devlearn.experiment.plan import baseline_name
from devlearn.experiment.publish import LEARNING_FILE, seed_folder
from devlearn.experiment.runner import EXPERIMENT_COPY, EXPERIMENT_INFO
from devlearn.experiment.spec import Protocol, read_experiment
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
    pubs: list[_Publication], protocol: Protocol, metrics: list[str]
) -> dict[str, Any]:
    """Each arm's ``metrics`` under ``protocol`` (mean and 95% t-interval over the seeds that
    report it, every seed's value) and each baseline's (its one evaluation)."""
    arms = []
    for arm_name in _arm_names(pubs):
        summaries = {
            str(seed): summary
            for seed, run in _runs(pubs, arm_name)
            if (summary := read_json(run / protocol.folder / "eval.json")) is not None
        }
        figures: dict[str, dict[str, Any]] = {}
        for key in metrics:
            values = {s: metric_value(v, key) for s, v in summaries.items()}
            found = {s: v for s, v in values.items() if v is not None}
            figures[key] = {**mean_ci(list(found.values())), "seeds": found}
        arms.append({"arm": arm_name, "metrics": figures})
    baselines = []
    for policy, summary in _baselines(pubs, protocol):
        evaluated = {key: metric_value(summary, key) for key in metrics}
        baselines.append({"baseline": policy, "metrics": evaluated})
    return {"keys": metrics, "arms": arms, "baselines": baselines}


def _arm_row(
    pubs: list[_Publication], arm_name: str, protocol: Protocol, headline: str
) -> tuple[dict[str, Any], str | None]:
    """One arm's figures under ``protocol`` over its seeds in every publication, and the
    eval.json key of its headline."""
    values: dict[str, float] = {}
    seconds: dict[str, float] = {}
    key = None
    for seed, run in _runs(pubs, arm_name):
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
        "learner": next(p.spec.arm(arm_name).learner for p in pubs if p.has(arm_name)),
        **stats,
        "seeds": values,
        "learn_s": {**mean_ci(list(seconds.values())), "seeds": seconds} if seconds else None,
    }
    return row, key


class _Publication:
    """One publication's folder, experiment file and record."""

    def __init__(self, dest: str | Path) -> None:
        self.dest = Path(dest)
        info = read_json(self.dest / EXPERIMENT_INFO)
        if info is None or "published" not in info or not (self.dest / EXPERIMENT_COPY).is_file():
            raise UsageError(
                f"{self.dest} is not a published experiment (no {EXPERIMENT_INFO} and "
                f"{EXPERIMENT_COPY} written by devlearn experiment publish)"
            )
        self.info: dict[str, Any] = info
        self.spec = read_experiment(self.dest / EXPERIMENT_COPY)

    def has(self, arm_name: str) -> bool:
        return any(arm.name == arm_name for arm in self.spec.arms)

    def protocol(self, name: str) -> Protocol | None:
        return next((p for p in self.spec.protocols if p.name == name), None)


def _arm_names(pubs: list[_Publication]) -> list[str]:
    """Every arm's name, the first publication's order first."""
    names: list[str] = []
    for pub in pubs:
        names += [arm.name for arm in pub.spec.arms if arm.name not in names]
    return names


def _runs(pubs: list[_Publication], arm_name: str) -> list[tuple[int, Path]]:
    """``(seed, run folder)`` of ``arm_name`` in every publication that has it."""
    return [
        (seed, pub.dest / arm_name / seed_folder(seed))
        for pub in pubs
        if pub.has(arm_name)
        for seed in pub.spec.seeds
    ]


def _baselines(pubs: list[_Publication], protocol: Protocol) -> list[tuple[str, dict[str, Any]]]:
    """Each baseline's evaluation under ``protocol``: the first publication's that has one."""
    found: dict[str, dict[str, Any]] = {}
    for pub in pubs:
        for policy in pub.spec.baselines:
            summary = read_json(pub.dest / baseline_name(policy) / protocol.folder / "eval.json")
            if summary is not None and policy not in found:
                found[policy] = summary
    return list(found.items())


RUN_CONFIGS = ("config.json", "run_config.json")
"""A published run's resolved config: devlearn's, or an outside learner's run config."""
NOT_NUMBERS = frozenset({"seed", "out_dir", "logger", "wandb_project", "save_interval"})
"""Resolved-config keys that do not decide a run's numbers beyond its seed."""


def _resolved(pub: _Publication, arm_name: str) -> dict[str, Any] | None:
    """The resolved config of ``arm_name``'s first recorded seed, flattened, without the keys
    that do not decide its numbers; None where none is published."""
    from devlearn.evaluation.report import flatten

    for _seed, run in _runs([pub], arm_name):
        for name in RUN_CONFIGS:
            config = read_json(run / name)
            if config is not None:
                return flatten({k: v for k, v in config.items() if k not in NOT_NUMBERS})
    return None


def _trained_alike(
    a: _Publication, b: _Publication, arm_name: str, ignore: Sequence[str] = ()
) -> str | None:
    """None where ``arm_name`` trained alike in ``a`` and ``b``, else what differs: the
    experiment files' training settings and the arm's, or failing those the resolved configs
    of its runs (the keys both record: a key added later was its default then), without the
    keys ``ignore`` names or lies under (``network``: every ``network.*``), which the reader
    declares do not decide the arm's numbers (another learner's unused network settings)."""
    same_files = a.spec.train.what() == b.spec.train.what()
    if same_files and a.spec.arm(arm_name).what() == b.spec.arm(arm_name).what():
        return None
    mine, theirs = _resolved(a, arm_name), _resolved(b, arm_name)
    if mine is None or theirs is None:
        return (
            f"its settings differ ({b.spec.train.what()} {b.spec.arm(arm_name).what()} against "
            f"{a.spec.train.what()} {a.spec.arm(arm_name).what()}) and no resolved config "
            "is published to compare"
        )

    def ignored(key: str) -> bool:
        return any(key == name or key.startswith(name + ".") for name in ignore)

    shared = mine.keys() & theirs.keys()
    differ = sorted(k for k in shared if mine[k] != theirs[k] and not ignored(k))
    if not differ:
        return None
    shown = ", ".join(f"{k}: {theirs[k]!r} against {mine[k]!r}" for k in differ[:4])
    return f"its resolved config differs in {len(differ)} key(s) ({shown})"


def _check_pooled(pubs: list[_Publication], ignore: Sequence[str] = ()) -> None:
    """Refuse publications whose same-named arms or protocols would mix different numbers.

    Raises:
        UsageError: Another behaviour, an arm trained otherwise (:func:`_trained_alike`), a
            protocol of the same name defined otherwise, or one seed of one arm in two
            publications.
    """
    first = pubs[0]
    for pub in pubs[1:]:
        where = f"{pub.dest} cannot be pooled with {first.dest}"
        if pub.spec.behavior != first.spec.behavior:
            raise UsageError(f"{where}: behaviour {pub.spec.behavior}, not {first.spec.behavior}")
        for protocol in pub.spec.protocols:
            mine = first.protocol(protocol.name)
            if mine is not None and mine.what() != protocol.what():
                raise UsageError(
                    f"{where}: protocol {protocol.name} is {protocol.what()} there, "
                    f"{mine.what()} in the first"
                )
    seen: dict[tuple[str, int], Path] = {}
    owner: dict[str, _Publication] = {}
    for pub in pubs:
        for arm in pub.spec.arms:
            if arm.name in owner:
                differs = _trained_alike(owner[arm.name], pub, arm.name, ignore)
                if differs:
                    raise UsageError(
                        f"arm {arm.name} in {pub.dest} is not the arm of the same name in "
                        f"{owner[arm.name].dest}: {differs}; rename one, or name the keys that "
                        "do not decide its numbers (--ignore-config KEY)"
                    )
            owner.setdefault(arm.name, pub)
            for seed in pub.spec.seeds:
                if (arm.name, seed) in seen:
                    raise UsageError(
                        f"arm {arm.name} seed {seed} is in both {seen[arm.name, seed]} and "
                        f"{pub.dest}: each seed of an arm must be in one publication"
                    )
                seen[arm.name, seed] = pub.dest


def _paired(rows: list[dict[str, Any]], versus: str) -> None:
    """Add to each row its paired difference from arm ``versus`` (``paired``: mean and 95%
    t-interval of row minus ``versus`` over the seeds both have, with those seeds)."""
    other = next((row for row in rows if row["arm"] == versus), None)
    for row in rows:
        if row is other or other is None:  # a protocol that arm was not evaluated under
            row["paired"] = None
            continue
        common = [s for s in row["seeds"] if s in other["seeds"]]
        differences = [row["seeds"][s] - other["seeds"][s] for s in common]
        row["paired"] = {**mean_ci(differences), "versus": versus, "seeds": common}


def experiment_table(
    dest: str | Path | Sequence[str | Path],
    metrics: list[str] | tuple[str, ...] = (),
    versus: str | None = None,
    ignore_config: Sequence[str] = (),
) -> dict[str, Any]:
    """The figures of publication ``dest`` (or of several, pooled: module docstring), per
    protocol: each arm's headline (the behaviour's, as ``devlearn eval``'s summary picks it:
    the per-episode mean where the evaluator reports one) as the mean and 95% t-interval over
    seeds (:func:`devlearn.api.stats.mean_ci`) with every seed's value and its seconds of
    learning where recorded; each baseline's headline under the same protocol (with its
    interval over episodes); the references of the protocol with their source. Each of
    ``metrics`` (an eval.json number by its dotted key) adds, per protocol, the same figures
    for that number (``"metrics"``: arms over seeds, baselines as evaluated). ``versus`` (an
    arm) adds each other arm's paired difference from it (``"paired"``). ``ignore_config``:
    resolved-config keys that pooled arms may differ in (:func:`_trained_alike`).

    Raises:
        UsageError: A ``dest`` is not a publication, publications that cannot be pooled, no
            evaluation has one of ``metrics``, or no arm is named ``versus``.
    """
    dests = [dest] if isinstance(dest, (str, Path)) else list(dest)
    pubs = [_Publication(d) for d in dests]
    _check_pooled(pubs, ignore_config)
    if versus is not None and versus not in _arm_names(pubs):
        names = ", ".join(_arm_names(pubs))
        raise UsageError(f"--versus {versus}: no such arm (the arms: {names})")
    first = pubs[0]
    spec, info = first.spec, first.info
    headline = str(info.get("headline_metric") or "")
    tables = []
    for protocol in spec.protocols:
        pooled = [pub for pub in pubs if pub.protocol(protocol.name) is not None]
        arms, keys = [], []
        for arm_name in _arm_names(pooled):
            row, key = _arm_row(pooled, arm_name, protocol, headline)
            arms.append(row)
            keys.append(key)
        if versus is not None:
            _paired(arms, versus)
        baselines = []
        for policy, summary in _baselines(pooled, protocol):
            found = _headline(summary, headline)
            if found is None:
                continue
            keys.append(found[0])
            low, high = found[2] if found[2] else (None, None)
            baselines.append(
                {"baseline": policy, "value": found[1], "ci_low": low, "ci_high": high}
            )
        references: list[dict[str, Any]] = []
        for pub in pooled:
            for ref in pub.spec.references:
                for figure_row in ref.rows if ref.protocol == protocol.name else ():
                    entry = {
                        "label": figure_row.label,
                        "value": figure_row.value,
                        "ci_low": figure_row.low,
                        "ci_high": figure_row.high,
                        "source": ref.source,
                        "note": ref.note,
                        "metrics": dict(figure_row.metrics),
                    }
                    if entry not in references:
                        references.append(entry)
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
            table["metrics"] = _metric_rows(pooled, protocol, list(metrics))
            table["metrics"]["references"] = [
                {"label": ref["label"], "source": _source(ref), "metrics": ref["metrics"]}
                for ref in references
                if any(key in ref["metrics"] for key in metrics)
            ]
        tables.append(table)
    for key in metrics:
        if not any(_has_metric(t["metrics"], key) for t in tables):
            raise UsageError(
                f"--metric {key}: no evaluation in {', '.join(map(str, dests))} has a number "
                "there (a dotted key of eval.json, e.g. likeness.touches_per_minute or "
                "episode_balance_mean)"
            )
    commits = [c for pub in pubs for c in pub.info.get("commits", []) or [pub.info.get("commit")]]
    table_info: dict[str, Any] = {
        "experiment": " + ".join(pub.spec.name for pub in pubs),
        "behavior": spec.behavior,
        "description": spec.description,
        "headline_metric": headline,
        "commit": info.get("commit"),
        "commits": list(dict.fromkeys(c for c in commits if c)),
        "published": info.get("published"),
        "seeds": sorted({seed for pub in pubs for seed in pub.spec.seeds}),
        "protocols": tables,
    }
    if len(pubs) > 1:
        table_info["publications"] = [str(pub.dest) for pub in pubs]
        table_info["ignored_config"] = list(ignore_config)
    return table_info


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
    if table.get("publications"):
        lines += [
            "Pooled publications (an arm's seeds from each that has it): "
            + ", ".join(table["publications"])
            + "."
            + (
                " Resolved configs compared without: " + ", ".join(table["ignored_config"]) + "."
                if table.get("ignored_config")
                else ""
            ),
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
        versus = next((a["paired"]["versus"] for a in protocol["arms"] if a.get("paired")), None)
        header += [f"paired with {versus} (same seeds)"] if versus else []
        extra = int(seconds) + int(versus is not None)
        lines += ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
        for arm in protocol["arms"]:
            per_seed = ", ".join(f"{s}: {figure(v)}" for s, v in arm["seeds"].items())
            cells = [arm["arm"], str(arm["n"]), _interval(arm), per_seed or "-"]
            if seconds:
                cells.append(_interval(arm["learn_s"]) if arm["learn_s"] else "-")
            if versus:
                paired = arm.get("paired")
                cells.append(f"{_interval(paired)} ({paired['n']} seeds)" if paired else "-")
            lines.append("| " + " | ".join(cells) + " |")
        for base in protocol["baselines"]:
            value = figure(base["value"])
            if base["ci_low"] is not None:
                value += f" [{figure(base['ci_low'])}, {figure(base['ci_high'])}] over episodes"
            cells = [f"{base['baseline']} actions (baseline)", "-", value, "-"]
            lines.append("| " + " | ".join(cells + ["-"] * extra) + " |")
        for ref in protocol["references"]:
            if ref["value"] is None:  # figures for --metric columns only
                continue
            source = _source(ref)
            if source not in sources:
                sources.append(source)
            number = sources.index(source) + 1
            cells = [f"{ref['label']} (reference [{number}])", "-"]
            cells += [_interval({"mean": ref["value"], **ref}), "-"]
            lines.append("| " + " | ".join(cells + ["-"] * extra) + " |")
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
