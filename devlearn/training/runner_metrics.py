"""The runner's metrics: one metrics.jsonl line and a progress-bar refresh per iteration
(:class:`MetricsLog`, held by :class:`~devlearn.training.runner.DevRunner`), and TensorBoard told
what a resumed run redoes."""

from __future__ import annotations

import json
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from tqdm import tqdm

from devlearn.env.behavior_env import EPISODE_RECORD

if TYPE_CHECKING:
    from torch.utils.tensorboard import SummaryWriter

    from devlearn.api.behavior import RunMetrics
    from devlearn.api.curriculum import Curriculum
    from devlearn.training.learned_rewards import LearnedRewards

EPISODES_AVERAGED = 100
"""Finished episodes whose reward terms and metrics each metrics.jsonl row averages."""


def headline_key(metric: str) -> str:
    """The metrics.jsonl key of a behaviour's headline as evaluation measures it: the
    per-episode mean, named as eval.json names it (``metrics/episode_score_mean`` for
    self-touch's ``score``), so that training, ``devlearn curve``, ``devlearn eval`` and
    ``devlearn report`` headline one figure under one name (issue #55)."""
    return f"metrics/episode_{metric}_mean"


@dataclass
class IterationFigures:
    """What one PPO iteration measured, as :meth:`MetricsLog.record` records it."""

    iteration: int
    """The iteration's index (from 0)."""
    env_steps: int
    """Physics steps done after it (all envs and ranks)."""
    finished: list[dict[str, float]]
    """Its finished episodes' figures (their records taken out by
    :meth:`MetricsLog.add_episode_records`)."""
    mean_step_reward: float
    """Its mean reward per step."""
    losses: dict[str, float]
    """PPO's losses."""
    steps_per_s: float
    """Physics steps per second (collecting and updating)."""
    times: dict[str, float]
    """Its ``collect_s`` (rollout) and ``update_s`` (PPO) seconds and ``update_threads``."""
    health: dict[str, float] = field(default_factory=dict)
    """The learner's figures (:mod:`devlearn.training.health`), also shown on the progress bar
    (empty: none)."""
    age_months: float | None = None
    """The body's age during the iteration (a row has ``age_months`` only where it is set: a
    run at an age or growing)."""


class MetricsLog:
    """What each iteration records: a metrics.jsonl row (steps, stage, speed, the last
    :data:`EPISODES_AVERAGED` episodes' rewards and metrics, losses, the behaviour's run
    metrics, learner health, learned rewards), the TensorBoard scalars rsl-rl's logger does
    not write, and the progress bar.

    Args:
        run_dir: Where metrics.jsonl is (appended to).
        curriculum: The behaviour's curriculum (the stage each row names).
        learned: The run's learned rewards (their figures join each row).
        run_metrics: The behaviour's run metrics (None: it has none), fed every finished
            episode's record and logged as ``metrics/<name>``.
        headline_metric: The behaviour's headline: its per-episode mean over the averaged
            episodes is logged and shown on the progress bar as :func:`headline_key`.
        is_main: Whether this rank writes (the others keep only :attr:`last_row`).
    """

    def __init__(
        self,
        run_dir: Path,
        curriculum: Curriculum,
        learned: LearnedRewards,
        run_metrics: RunMetrics | None,
        headline_metric: str = "",
        is_main: bool = True,
    ) -> None:
        self.run_dir = Path(run_dir)
        self.curriculum = curriculum
        self.learned = learned
        self.run_metrics = run_metrics
        self.headline_metric = headline_metric
        self.is_main = is_main
        self.episodes: deque[dict[str, float]] = deque(maxlen=EPISODES_AVERAGED)
        """The last finished episodes' figures (``reward/<term>``, ``metrics/<name>``...)."""
        self.last_row: dict[str, Any] = {}
        """The last row recorded."""

    def add_episode_records(
        self,
        finished: list[dict[str, Any]],
        all_ranks: Callable[[Any], list[Any]] | None = None,
    ) -> None:
        """Take the episode records out of ``finished`` (so only numbers are averaged) and give
        them to the run metrics: every rank's in rank order when ``all_ranks`` (a collective)
        is given."""
        records = [ep.pop(EPISODE_RECORD) for ep in finished if EPISODE_RECORD in ep]
        if self.run_metrics is None:
            return
        if all_ranks is not None:
            records = [r for rank in all_ranks(records) for r in rank]
        self.run_metrics.add(records)

    def record(
        self, figures: IterationFigures, bar: tqdm, writer: SummaryWriter | None
    ) -> dict[str, Any]:
        """Add the iteration's finished episodes, append one line to metrics.jsonl, write the
        extra TensorBoard scalars and refresh the progress bar (rank 0); return the row.

        Args:
            figures: What the iteration measured.
            bar: The progress bar.
            writer: rsl-rl's writer (TensorBoard, W&B...; None: none).
        """
        finished, health, env_steps = figures.finished, figures.health, figures.env_steps
        rate, age_months = figures.steps_per_s, figures.age_months
        self.episodes.extend(finished)
        row: dict[str, Any] = {
            "step": env_steps,
            "iteration": figures.iteration,
            "stage": self.curriculum.stage.name,
            **({} if age_months is None else {"age_months": age_months}),
            "steps_per_s": rate,
            **figures.times,
            "episodes": len(finished),
            "mean_step_reward": figures.mean_step_reward,
            "mean_reward": None,
        }
        if self.episodes:
            returns = [
                sum(v for k, v in ep.items() if k.startswith("reward/")) for ep in self.episodes
            ]
            row["mean_reward"] = float(np.mean(returns))
            for key in dict.fromkeys(k for ep in self.episodes for k in ep):
                row[key] = float(np.mean([ep[key] for ep in self.episodes if key in ep]))
        per_episode = f"metrics/{self.headline_metric}"  # averaged over episodes, not a run metric
        if self.headline_metric and any(per_episode in ep for ep in self.episodes):
            row[headline_key(self.headline_metric)] = row[per_episode]
        row.update({f"loss/{k}": float(v) for k, v in figures.losses.items()})
        run_metrics = {}
        if self.run_metrics is not None:
            run_metrics = {f"metrics/{k}": float(v) for k, v in self.run_metrics.values().items()}
        row.update(run_metrics)
        row.update(health)
        row.update(self.learned.last)
        self.last_row = row
        if not self.is_main:
            return row
        it = figures.iteration
        self.learned.write(writer, it)
        if writer is not None:
            for key, value in health.items():
                writer.add_scalar(key if "/" in key else f"health/{key}", value, it)
            for key, value in run_metrics.items():
                writer.add_scalar(key, value, it)
        with open(self.run_dir / "metrics.jsonl", "a") as f:
            f.write(json.dumps(row) + "\n")
        self._show(row, rate, health, bar, env_steps)
        return row

    def _show(
        self,
        row: dict[str, Any],
        rate: float,
        health: dict[str, float],
        bar: tqdm,
        env_steps: int,
    ) -> None:
        """The progress bar: steps done, and speed, stage, health and reward beside it."""
        postfix = {"steps/s": f"{rate:.0f}", "stage": row["stage"]}
        if health:
            postfix["std"] = f"{health['health/std_mean']:.2f}"
            postfix["sat"] = f"{health['health/saturated']:.0%}"
            postfix["ev"] = f"{health['health/explained_variance']:.2f}"
        if row["mean_reward"] is not None:
            postfix["reward"] = f"{row['mean_reward']:.3g}"
        for key in (headline_key(self.headline_metric), f"metrics/{self.headline_metric}"):
            if self.headline_metric and row.get(key) is not None:  # the per-episode one first
                postfix[key.removeprefix("metrics/")] = f"{row[key]:.3g}"
                break
        bar.set_postfix(postfix, refresh=False)
        total = getattr(bar, "total", None) or env_steps
        if env_steps >= total:  # the last iteration: stop at the total; close() draws it once
            bar.n = total
        else:
            bar.update(env_steps - bar.n)


def purge_tensorboard_from(writer: SummaryWriter | None, step: int) -> None:
    """Tell TensorBoard to hide earlier event files' points at ``step`` and later (a resumed
    run redoes the iterations a killed run logged after its last checkpoint): the
    ``SessionLog.START`` event that ``SummaryWriter(purge_step=...)`` writes."""
    file_writer = getattr(writer, "file_writer", None)
    if file_writer is None:
        return
    from tensorboard.compat.proto.event_pb2 import Event, SessionLog

    file_writer.add_event(Event(step=step, session_log=SessionLog(status=SessionLog.START)))
