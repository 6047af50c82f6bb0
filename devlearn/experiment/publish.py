"""publish_experiment(): from an experiment folder, what a reader needs, small enough to commit.

Layout of a publication (``devlearn experiment table DEST`` reads it)::

    DEST/experiment.toml                  the experiment file
    DEST/experiment.json                  name, behaviour and headline, the commit(s) that ran,
                                          each run's, each arm's policy (which seed, why), what
                                          was not evaluated yet
    DEST/ARM/seed=S/eval_P/eval.json      every evaluation, per arm, seed and protocol
    DEST/ARM/seed=S/config.json           the run's resolved config (SB3 arms: run_config.json,
                                          the config devlearn's Gymnasium env resolved, and
                                          train.json, SB3's own record)
    DEST/ARM/seed=S/learning.json         steps trained and seconds of learning
    DEST/ARM/seed=S/curve.jsonl           the training curve, thinned (devlearn arms)
    DEST/ARM/policy.pt                    the policy of the arm's median seed
    DEST/baseline_B/eval_P/eval.json      every baseline's evaluation, per protocol
"""

from __future__ import annotations

import json
import math
import os
import shutil
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from devlearn.api.errors import UsageError
from devlearn.experiment.plan import CHECKPOINT, SCRIPTED_POLICY, baseline_name, run_name
from devlearn.experiment.runner import EXPERIMENT_COPY, EXPERIMENT_INFO
from devlearn.experiment.spec import Arm, ExperimentSpec, read_experiment
from devlearn.files import copy_atomically, write_text_atomically
from devlearn.sweep.bookkeeping import now
from devlearn.sweep.job import read_json, write_json

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry

CURVE_ROWS = 50
"""Most rows of a published training curve (every k-th row of metrics.jsonl, and the last)."""
CURVE_COLUMNS = ("step", "iteration", "stage", "mean_reward", "collect_s", "update_s")
"""metrics.jsonl columns a published curve keeps, with the behaviour's headline
(``metrics/HEADLINE``, its per-episode mean ``metrics/episode_HEADLINE_mean`` and
``metrics/training_HEADLINE``, those a run logs)."""
HEADLINE_COLUMNS = ("{headline}", "episode_{headline}_mean", "training_{headline}")
"""The headline's metrics.jsonl columns a published curve keeps (after ``metrics/``)."""
LEARNING_FILE = "learning.json"
"""A published run's steps trained and seconds of learning."""
CURVE_FILE = "curve.jsonl"
"""A published run's thinned training curve."""
POLICY_FILE = "policy.pt"
"""An arm's published policy (DEST/ARM/policy.pt)."""


def seed_folder(seed: int) -> str:
    """A published run's folder under its arm: ``seed=S``."""
    return f"seed={seed}"


def _rows(path: Path) -> list[dict[str, Any]]:
    """metrics.jsonl's complete rows."""
    rows = []
    try:
        lines = path.read_text().splitlines()
    except OSError:
        return []
    for line in lines:
        try:
            row = json.loads(line)
        except ValueError:  # a line being written when the run was stopped
            continue
        if isinstance(row, dict):
            rows.append(row)
    return rows


def thin_curve(rows: list[dict[str, Any]], headline: str) -> list[dict[str, Any]]:
    """Every k-th row (and the last) with a few columns, at most :data:`CURVE_ROWS` rows."""
    if not rows:
        return []
    every = max(1, math.ceil(len(rows) / CURVE_ROWS))
    columns = [*CURVE_COLUMNS, *(f"metrics/{k}" for k in HEADLINE_COLUMNS)]
    columns = [c.format(headline=headline) for c in columns]
    kept = [r for i, r in enumerate(rows) if (i + 1) % every == 0 or i == len(rows) - 1]
    return [{k: row[k] for k in columns if k in row} for row in kept]


def learning_of(run_dir: Path, arm: Arm, rows: list[dict[str, Any]]) -> dict[str, Any] | None:
    """Steps trained and seconds of learning of one run: devlearn's collect + update summed
    over metrics.jsonl's rows, SB3's seconds inside ``learn()`` (train.json's ``learn_s``)."""
    if arm.learner != "devlearn":
        train = read_json(run_dir / "train.json")
        if not train or "learn_s" not in train:
            return None
        return {
            "learner": arm.learner,
            "env_steps": train.get("env_steps"),
            "learn_s": train["learn_s"],
            "source": "train.json: learn_s, the seconds inside SB3's learn()",
        }
    if not rows:
        return None
    return {
        "learner": arm.learner,
        "env_steps": rows[-1].get("step"),
        "learn_s": sum(r.get("collect_s", 0.0) + r.get("update_s", 0.0) for r in rows),
        "iterations": len(rows),
        "source": "metrics.jsonl: collect_s + update_s of every row",
    }


def median_seed(values: dict[int, float]) -> int:
    """The seed of the median value (the lower of the two middle ones for an even count;
    ties by seed)."""
    ranked = sorted(values, key=lambda seed: (values[seed], seed))
    return ranked[(len(ranked) - 1) // 2]


def _check_dest(out: Path, dest: Path) -> None:
    if dest.exists() and not dest.is_dir():
        raise UsageError(f"{dest} is a file; give a folder to publish into")
    if dest.resolve() == out.resolve() or out.resolve() in dest.resolve().parents:
        raise UsageError(f"{dest} is inside the experiment folder {out}; publish elsewhere")
    if dest.is_dir() and any(dest.iterdir()):
        earlier = read_json(dest / EXPERIMENT_INFO)
        if not earlier or "published" not in earlier:
            raise UsageError(
                f"{dest} holds something other than a publication; give a new or empty folder "
                "(an earlier publication there is replaced)"
            )


def _publish_run(
    spec: ExperimentSpec, arm: Arm, seed: int, out: Path, target: Path, headline: str
) -> dict[str, Any] | None:
    """One run's evaluations, config, learning figures and curve into ``target``; what
    experiment.json says of it (None: not evaluated yet)."""
    name = run_name(arm.name, seed)
    run_dir = out / "runs" / name
    evaluated = []
    for protocol in spec.protocols:
        source = run_dir / protocol.folder / "eval.json"
        if read_json(source) is None:
            continue
        (target / protocol.folder).mkdir(parents=True, exist_ok=True)
        copy_atomically(source, target / protocol.folder / "eval.json")
        evaluated.append(protocol.name)
    if not evaluated:
        return None
    kept = ["config.json"] if arm.learner == "devlearn" else ["run_config.json", "train.json"]
    for file in kept:
        if (run_dir / file).is_file():
            copy_atomically(run_dir / file, target / file)
    rows = _rows(run_dir / "metrics.jsonl")
    learning = learning_of(run_dir, arm, rows)
    if learning is not None:
        write_json(target / LEARNING_FILE, learning)
    curve = thin_curve(rows, headline)
    if curve:
        text = "".join(json.dumps(row) + "\n" for row in curve)
        write_text_atomically(target / CURVE_FILE, text)
    record = read_json(out / "records" / f"{name}.json") or {}
    commits = sorted({a["commit"] for a in record.get("attempts", []) if a.get("commit")})
    return {
        "arm": arm.name,
        "learner": arm.learner,
        "seed": seed,
        "evaluated": evaluated,
        "commits": commits,
        "dirty": any(a.get("dirty") for a in record.get("attempts", [])),
        "wall_s": record.get("wall_s"),
    }


def publish_experiment(
    out: str | Path, dest: str | Path, registry: PluginRegistry, stream: TextIO | None = None
) -> dict[str, Any]:
    """Publish experiment folder ``out`` into ``dest`` (replacing an earlier publication there).

    Kept: every evaluation's eval.json (arms x seeds x protocols, baselines x protocols), per
    run its config, seconds of learning and a thinned training curve, one policy file per arm
    (the seed whose headline under the first protocol is the median over seeds; devlearn's
    checkpoint slimmed as ``devlearn slim`` does, an SB3 arm's scripted policy as it is), the
    experiment file and the commit. Runs not evaluated yet are listed, not published.

    Args:
        out: The folder ``devlearn experiment run`` wrote.
        dest: Where to publish (new, empty, or an earlier publication).
        registry: Plugin registry (the behaviour's headline; slimming a checkpoint).
        stream: Where to say what was published (None: nowhere).
    Returns:
        What ``dest/experiment.json`` holds.
    Raises:
        UsageError: ``out`` holds no experiment, or ``dest`` holds something else.
    """
    from devlearn.evaluation.policy_file import slim_checkpoint
    from devlearn.evaluation.report import headline_of

    out, dest = Path(out), Path(dest)
    info = read_json(out / EXPERIMENT_INFO)
    if info is None or not (out / EXPERIMENT_COPY).is_file():
        raise UsageError(
            f"{out} is not an experiment folder (no readable {EXPERIMENT_INFO} and "
            f"{EXPERIMENT_COPY}); give the OUT of devlearn experiment run"
        )
    spec = read_experiment(out / EXPERIMENT_COPY)
    headline = registry.behavior(spec.behavior).about.headline_metric
    _check_dest(out, dest)
    staging = dest.parent / f".{dest.name}.publishing-{os.getpid()}"
    shutil.rmtree(staging, ignore_errors=True)
    runs: dict[str, Any] = {}
    policies: dict[str, Any] = {}
    missing: list[str] = []
    first = spec.protocols[0]
    try:
        staging.mkdir(parents=True)
        write_text_atomically(staging / EXPERIMENT_COPY, spec.text)
        for policy in spec.baselines:
            name = baseline_name(policy)
            for protocol in spec.protocols:
                source = out / "runs" / name / protocol.folder / "eval.json"
                if read_json(source) is None:
                    missing.append(f"{name}/{protocol.folder}")
                    continue
                (staging / name / protocol.folder).mkdir(parents=True, exist_ok=True)
                copy_atomically(source, staging / name / protocol.folder / "eval.json")
        for arm in spec.arms:
            values: dict[int, float] = {}
            for seed in spec.seeds:
                name = run_name(arm.name, seed)
                target = staging / arm.name / seed_folder(seed)
                published = _publish_run(spec, arm, seed, out, target, headline)
                if published is None:
                    missing.append(name)
                    continue
                runs[name] = published
                missing += [f"{name}/eval_{p}" for p in _absent(spec, published)]
                summary = read_json(target / first.folder / "eval.json")
                found = headline_of(summary or {}, headline)
                if found is not None:
                    values[seed] = found[1]
            if not values:
                continue
            seed = median_seed(values)
            run_dir = out / "runs" / run_name(arm.name, seed)
            if arm.learner == "devlearn":
                slim_checkpoint(run_dir / CHECKPOINT, staging / arm.name / POLICY_FILE, registry)
            else:
                copy_atomically(run_dir / SCRIPTED_POLICY, staging / arm.name / POLICY_FILE)
            policies[arm.name] = {
                "file": f"{arm.name}/{POLICY_FILE}",
                "seed": seed,
                "chosen_by": f"the median over seeds of the headline under protocol '{first.name}'",
                "values": {str(s): v for s, v in sorted(values.items())},
            }
        commits = sorted({c for r in runs.values() for c in r["commits"]})
        published = {
            "name": spec.name,
            "behavior": spec.behavior,
            "headline_metric": headline,
            "description": spec.description,
            "published": now(),
            "source": str(out.resolve()),
            "commit": (info.get("commit") or {}).get("commit"),
            "commits": commits,
            "dirty": any(r["dirty"] for r in runs.values()),
            "file": EXPERIMENT_COPY,
            "runs": runs,
            "policies": policies,
            "missing": missing,
        }
        write_json(staging / EXPERIMENT_INFO, published)
        _replace(staging, dest)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    if stream is not None:
        size = sum(p.stat().st_size for p in dest.rglob("*") if p.is_file())
        evaluations = sum(1 for _ in dest.rglob("eval.json"))
        print(
            f"published {spec.name} into {dest}: {evaluations} evaluations of {len(runs)} runs "
            f"and {len(spec.baselines)} baseline(s), {len(policies)} policy file(s), "
            f"{size / 1e6:.1f} MB; commit {published['commit']}",
            file=stream,
        )
        if missing:
            print(f"not evaluated yet, not published: {', '.join(missing)}", file=stream)
    return published


def _absent(spec: ExperimentSpec, published: dict[str, Any]) -> list[str]:
    return [p.name for p in spec.protocols if p.name not in published["evaluated"]]


def _replace(staging: Path, dest: Path) -> None:
    """Put the staged publication at ``dest``, the earlier one (if any) removed."""
    if dest.is_dir() and not any(dest.iterdir()):
        dest.rmdir()
    if not dest.exists():
        staging.rename(dest)
        return
    old = dest.parent / f".{dest.name}.replaced-{os.getpid()}"
    dest.rename(old)
    staging.rename(dest)
    shutil.rmtree(old, ignore_errors=True)
