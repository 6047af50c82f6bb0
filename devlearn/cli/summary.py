"""What ``devlearn run`` prints at the end: where things are, how far it got, what to run next."""

from __future__ import annotations

import dataclasses
import shlex
from pathlib import Path
from typing import TYPE_CHECKING, Any

from devlearn.api.errors import UsageError
from devlearn.api.json_files import read_json, read_json_lines
from devlearn.evaluation.report import headline_of
from devlearn.training.checkpoint import LATEST
from devlearn.training.runner_metrics import EPISODES_AVERAGED, headline_key

if TYPE_CHECKING:
    from devlearn.config.run_config import RunConfig


def _rows(run_dir: Path) -> list[dict[str, Any]]:
    path = run_dir / "metrics.jsonl"
    if not path.exists():
        return []
    try:
        return read_json_lines(path)[0]  # a line cut short by a kill: skipped
    except UsageError:
        return []


def headline(rows: list[dict[str, Any]], metric: str) -> tuple[str, Any, Any]:
    """The metric to show, its first logged value and its last (None where never logged).

    ``metric`` is the behaviour's ``headline_metric``, logged per episode as evaluation
    measures it (:func:`~devlearn.training.runner_metrics.headline_key`,
    ``metrics/episode_<metric>_mean``; runs from before that logged ``metrics/<metric>``);
    without one, or before any episode logged it, the mean episode reward.
    """
    keys = (headline_key(metric), f"metrics/{metric}") if metric else ()
    for key in (*keys, "mean_reward"):
        values = [r[key] for r in rows if key and r.get(key) is not None]
        if values:
            return key, values[0], values[-1]
    return "mean_reward", None, None


def _number(value: Any) -> str:
    return "-" if value is None else f"{value:.4g}"


def paper_budget(presets: dict[str, dict[str, Any]]) -> tuple[str, int] | None:
    """``(preset, total_steps)`` of the behaviour's preset that sets the longest run (its
    ``paper`` preset for the built-in behaviours), or None when no preset sets one."""
    budgets = [
        (name, int(values["total_steps"]))
        for name, values in presets.items()
        if isinstance(values.get("total_steps"), (int, float))
    ]
    return max(budgets, key=lambda b: b[1]) if budgets else None


def baseline_dirs(behavior_name: str) -> dict[str, Path]:
    """Where ``devlearn eval BEHAVIOR --policy zero|random`` writes by default (this folder)."""
    return {p: Path(f"eval_{behavior_name}_{p}") for p in ("random", "zero")}


def run_calibration(behavior_config: Any, run_dir: Path) -> dict[str, str]:
    """``{"behavior.FIELD": path}`` for each field of the behaviour's config that names a file
    the run made in its folder (hand regard's ``detector_file``: the detector that babbling
    calibrated). A baseline evaluated without it is scored by no calibration at all (hand
    regard's ``detector`` figures are then 0), so the summary's baseline commands pass it:
    the run and its baselines are measured alike (issue #55)."""
    if behavior_config is None or not dataclasses.is_dataclass(behavior_config):
        return {}
    inside = run_dir.resolve()
    found = {}
    for field in dataclasses.fields(behavior_config):
        value = getattr(behavior_config, field.name)
        if not isinstance(value, str) or not value:
            continue
        path = Path(value)
        if path.is_file() and inside in path.resolve().parents:
            found[f"behavior.{field.name}"] = value
    return found


def _baseline_values(behavior_name: str, metric: str) -> dict[str, Any]:
    """The headline of the baseline evaluations already in their default folders, as ``devlearn
    eval`` headlines it (:func:`~devlearn.evaluation.report.headline_of`: the per-episode
    mean), so that it stands beside the run's per-episode figure."""
    found = {}
    for policy, folder in baseline_dirs(behavior_name).items():
        try:
            summary = read_json(folder / "eval.json")
        except UsageError:
            continue
        head = headline_of(summary, metric) if isinstance(summary, dict) else None
        if head is not None:
            found[policy] = head[1]
    return found


def run_summary(
    result: Any,
    behavior_name: str,
    metric: str,
    total_steps: int,
    num_envs: int = 1,
    budget: tuple[str, int] | None = None,
    behavior_config: Any = None,
) -> str:
    """The lines printed when a run finishes.

    Args:
        result: The :class:`~devlearn.training.train.TrainResult`.
        behavior_name: The behaviour trained.
        metric: The behaviour's ``headline_metric``.
        total_steps: The run's step budget (for the resume hint).
        num_envs: Environments per rank (to say why no episode finished, if none did).
        budget: ``(preset, steps)`` of a full run (:func:`paper_budget`), if the behaviour
            has one: a shorter run is said to be a demonstration.
        behavior_config: The run's behaviour config: the files it names in the run folder
            (:func:`run_calibration`) go into the baseline commands.
    """
    run_dir = Path(result.run_dir)
    rows = _rows(run_dir)
    key, first, last = headline(rows, metric)
    folder = shlex.quote(str(run_dir))
    checkpoint = shlex.quote(str(run_dir / LATEST))
    first_step = rows[0]["step"] if rows else 0
    lines = [
        f"finished: {result.env_steps:,} environment steps, {result.iterations} iterations",
        f"  checkpoint  {run_dir / LATEST}",
        f"  logs        {run_dir / 'metrics.jsonl'}, TensorBoard: tensorboard --logdir {folder}",
    ]
    if last is None:
        per_env = result.env_steps // max(num_envs, 1)
        lines.append(
            f"  {key}  - (no episode finished: each of the {num_envs} environments ran "
            f"{per_env:,} steps, less than one episode; train longer for episode metrics)"
        )
    else:
        lines.append(
            f"  {key.removeprefix('metrics/')}  {_number(last)} now, {_number(first)} at the "
            f"start (step {first_step:,}), per episode over the last {EPISODES_AVERAGED} "
            "training episodes (actions sampled, the stage's start; devlearn eval measures it "
            "with the mean action under the evaluation protocol)"
        )
    stages: dict[str, int] = {}  # the curriculum stages the run went through, with where
    for row in rows:
        if row.get("stage"):
            stages.setdefault(str(row["stage"]), int(row.get("step", 0)))
    if stages:
        went = " -> ".join(f"{name} (logged from step {step:,})" for name, step in stages.items())
        lines.append(f"  stages      {went}")
    elif result.last.get("stage"):
        lines.append(f"  stage       {result.last['stage']}")
    lines += [f"  {warning}" for warning in result.warnings]  # the learner-health warnings
    if budget is not None and total_steps < budget[1]:
        lines.append(
            f"  budget      {total_steps:,} steps, {100 * total_steps / budget[1]:.2g}% of a full "
            f"run ({budget[1]:,}, --preset {budget[0]}): a demonstration; compare its "
            "evaluation with the baselines below"
        )
    baselines = _baseline_values(behavior_name, metric) if metric else {}
    dirs = baseline_dirs(behavior_name)
    if baselines:
        shown = ", ".join(f"{p} {_number(v)} ({dirs[p]})" for p, v in baselines.items())
        lines.append(
            f"  baselines   {headline_key(metric).removeprefix('metrics/')} under the "
            f"evaluation protocol: {shown}"
        )
    more = max(2 * total_steps, total_steps + 1)
    eval_dir = shlex.quote(str(run_dir / "eval"))
    lines += [
        "next:",
        f"  devlearn eval {behavior_name} --checkpoint {checkpoint} --episodes 100",
    ]
    missing = [p for p in dirs if p not in baselines]
    calibration = run_calibration(behavior_config, run_dir)
    same = "".join(f" --set {shlex.quote(f'{k}={v}')}" for k, v in calibration.items())
    why = " and this run's calibration" if calibration else ""
    lines += [
        f"  devlearn eval {behavior_name} --policy {p} --episodes 100{same}"
        f"   # baseline, same protocol{why}"
        for p in missing
    ]
    lines += [
        f"  devlearn report {eval_dir} {' '.join(str(d) for d in dirs.values())}"
        "   # the run beside the baselines",
        f"  devlearn curve {folder}",
        f"  devlearn run {behavior_name} --resume {folder} --steps {more:g}   # train longer",
    ]
    return "\n".join(lines)


def finished_message(run_dir: str | Path, cfg: RunConfig, found: tuple | None = None) -> str | None:
    """If the run's newest checkpoint already reached ``cfg.total_steps``, say so; else None.

    Reads only the newest checkpoint (or takes ``found``, the ``(path, state)`` of
    :func:`~devlearn.training.checkpoint.resume_checkpoint`), so nothing in the run is touched;
    a checkpoint that ``cfg`` could not continue (other behaviour or env count) is refused
    first, finished or not.
    """
    from devlearn.training.checkpoint import resume_checkpoint
    from devlearn.training.train import check_resumable

    path, state = found if found is not None else resume_checkpoint(run_dir)
    check_resumable(cfg, state, path)
    done = int(state.get("env_steps", 0))
    total_steps = cfg.total_steps
    if done < total_steps:
        return None
    return (
        f"run {run_dir} is already finished ({done:,} of {total_steps:,} steps); nothing was "
        f"written. To train longer: --resume {run_dir} --steps {max(2 * done, done + 1):g}"
    )
