"""DevRunner's metrics: one metrics.jsonl line and a progress-bar refresh per iteration, and
TensorBoard told what a resumed run redoes (a mixin of
:class:`~devlearn.training.runner.DevRunner`)."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Any

import numpy as np
from tqdm import tqdm

if TYPE_CHECKING:
    from collections import deque
    from pathlib import Path

    from torch.utils.tensorboard import SummaryWriter

    from devlearn.api.behavior import RunMetrics
    from devlearn.api.curriculum import Curriculum
    from devlearn.training.learned_rewards import LearnedRewards


class RunnerMetrics:
    """Per-iteration records for :class:`~devlearn.training.runner.DevRunner`.

    Uses the runner's ``env_steps``, ``curriculum``, ``episodes``, ``learned``,
    ``run_metrics``, ``is_main``, ``logger``, ``run_dir`` and ``headline_metric``; sets
    ``last_row``.
    """

    # What the host runner provides (DevRunner sets them), declared for the type checker:
    # annotations only, no values.
    env_steps: int
    curriculum: Curriculum
    episodes: deque[dict[str, float]]
    learned: LearnedRewards
    run_metrics: RunMetrics | None
    is_main: bool
    logger: Any  # rsl-rl's Logger (its writer: TensorBoard, W&B... or None)
    run_dir: Path
    headline_metric: str

    def _record(
        self,
        it: int,
        num_finished: int,
        mean_step_reward: float,
        losses: dict,
        rate: float,
        times: dict[str, float],
        bar: tqdm,
        health: dict[str, float] | None = None,
    ) -> None:
        """Append one line to metrics.jsonl and refresh the progress bar (rank 0).

        ``times`` holds the iteration's ``collect_s`` (rollout) and ``update_s`` (PPO) seconds;
        ``health`` the learner's figures (:mod:`devlearn.training.health`), also shown on the
        progress bar.
        """
        row: dict[str, Any] = {
            "step": self.env_steps,
            "iteration": it,
            "stage": self.curriculum.stage.name,
            "steps_per_s": rate,
            **times,
            "episodes": num_finished,
            "mean_step_reward": mean_step_reward,
            "mean_reward": None,
        }
        if self.episodes:
            returns = [
                sum(v for k, v in ep.items() if k.startswith("reward/")) for ep in self.episodes
            ]
            row["mean_reward"] = float(np.mean(returns))
            for key in dict.fromkeys(k for ep in self.episodes for k in ep):
                row[key] = float(np.mean([ep[key] for ep in self.episodes if key in ep]))
        row.update({f"loss/{k}": float(v) for k, v in losses.items()})
        run_metrics = {}
        if self.run_metrics is not None:
            run_metrics = {f"metrics/{k}": float(v) for k, v in self.run_metrics.values().items()}
        row.update(run_metrics)
        row.update(health or {})
        row.update(self.learned.last)
        self.last_row = row
        if not self.is_main:
            return
        self.learned.write(self.logger.writer, it)
        if self.logger.writer is not None:
            for key, value in (health or {}).items():
                self.logger.writer.add_scalar(key if "/" in key else f"health/{key}", value, it)
            for key, value in run_metrics.items():
                self.logger.writer.add_scalar(key, value, it)
        with open(self.run_dir / "metrics.jsonl", "a") as f:
            f.write(json.dumps(row) + "\n")
        postfix = {"steps/s": f"{rate:.0f}", "stage": row["stage"]}
        if health:
            postfix["std"] = f"{health['health/std_mean']:.2f}"
            postfix["sat"] = f"{health['health/saturated']:.0%}"
            postfix["ev"] = f"{health['health/explained_variance']:.2f}"
        if row["mean_reward"] is not None:
            postfix["reward"] = f"{row['mean_reward']:.3g}"
        headline = row.get(f"metrics/{self.headline_metric}")
        if headline is not None:
            postfix[self.headline_metric] = f"{headline:.3g}"
        bar.set_postfix(postfix, refresh=False)
        total = getattr(bar, "total", None) or self.env_steps
        if self.env_steps >= total:  # the last iteration: stop at the total; close() draws it once
            bar.n = total
        else:
            bar.update(self.env_steps - bar.n)


def purge_tensorboard_from(writer: SummaryWriter | None, step: int) -> None:
    """Tell TensorBoard to hide earlier event files' points at ``step`` and later (a resumed
    run redoes the iterations a killed run logged after its last checkpoint): the
    ``SessionLog.START`` event that ``SummaryWriter(purge_step=...)`` writes."""
    file_writer = getattr(writer, "file_writer", None)
    if file_writer is None:
        return
    from tensorboard.compat.proto.event_pb2 import Event, SessionLog

    file_writer.add_event(Event(step=step, session_log=SessionLog(status=SessionLog.START)))
