"""What ``devlearn run`` prints at the end: where things are, how far it got, what to run next."""

from __future__ import annotations

import json
import shlex
from pathlib import Path
from typing import Any

from devlearn.training.checkpoint import LATEST


def _rows(run_dir: Path) -> list[dict[str, Any]]:
    path = run_dir / "metrics.jsonl"
    if not path.exists():
        return []
    rows = []
    for line in path.read_text().splitlines():
        try:
            rows.append(json.loads(line))
        except ValueError:  # a line cut short by a kill: skip it
            continue
    return rows


def headline(rows: list[dict[str, Any]], metric: str) -> tuple[str, Any, Any]:
    """The metric to show, its first logged value and its last (None where never logged).

    ``metric`` is the behaviour's ``headline_metric`` (logged as ``metrics/<metric>``); without
    one, or before any episode logged it, the mean episode reward.
    """
    for key in (f"metrics/{metric}" if metric else "", "mean_reward"):
        values = [r[key] for r in rows if key and r.get(key) is not None]
        if values:
            return key, values[0], values[-1]
    return "mean_reward", None, None


def _number(value: Any) -> str:
    return "-" if value is None else f"{value:.4g}"


def run_summary(result: Any, behavior_name: str, metric: str, total_steps: int) -> str:
    """The lines printed when a run finishes.

    Args:
        result: The :class:`~devlearn.training.train.TrainResult`.
        behavior_name: The behaviour trained.
        metric: The behaviour's ``headline_metric``.
        total_steps: The run's step budget (for the resume hint).
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
        f"  {key}  {_number(last)} now, {_number(first)} at the start (step {first_step:,})",
    ]
    if result.last.get("stage"):
        lines.append(f"  stage       {result.last['stage']}")
    more = max(2 * total_steps, total_steps + 1)
    lines += [
        "next:",
        f"  devlearn eval {behavior_name} --checkpoint {checkpoint} --episodes 100",
        f"  devlearn curve {folder}",
        f"  devlearn run {behavior_name} --resume {folder} --steps {more:g}   # train longer",
    ]
    return "\n".join(lines)


def finished_message(run_dir: str | Path, cfg, found: tuple | None = None) -> str | None:
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
