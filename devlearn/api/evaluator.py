"""What a behaviour's evaluation records (:class:`Evaluator`) and what it keeps over a whole
run (:class:`RunMetrics`); :class:`~devlearn.api.capabilities.EvalProtocol` returns them. Kept
apart from :mod:`devlearn.api.behavior` so that the capabilities can name them without an
import circle."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

if TYPE_CHECKING:
    from devlearn.api.rewards import StepContext


class Evaluator:
    """Collects a behaviour's metrics over steps and episodes.

    The environment keeps one per sub-environment during training (each episode's
    :meth:`end_episode` metrics are logged under ``metrics/<key>``); ``devlearn eval`` keeps one
    over all evaluation episodes and prints :meth:`summary`.
    """

    mergeable: ClassVar[bool] = False
    """Whether :meth:`merge` is implemented (set it True where it is): ``devlearn eval`` then
    may play the episodes in several environments at once; False (the default): one after
    another in one environment (``devlearn.testing.check_behavior`` checks that the two
    agree)."""

    def record(self, ctx: StepContext) -> None:
        """Take note of one step."""

    def end_episode(self) -> dict[str, float]:
        """Close the current episode; return its metrics (name -> float)."""
        return {}

    def summary(self) -> dict[str, Any]:
        """Return the metrics over every episode recorded so far (JSON-serialisable)."""
        return {}

    def write_artifacts(self, out_dir: Path) -> list[Path]:
        """Write pictures or files that explain the summary; return their paths."""
        return []

    def protocol(self) -> dict[str, Any]:
        """How episodes are scored, recorded in every eval JSON under ``protocol``.

        Returns:
            JSON-serialisable, e.g. ``{"settle_steps": 10, "criteria": {...}, "headline": ...}``.
        """
        return {}

    def episode_record(self) -> Any:
        """What :class:`RunMetrics` need of the episode :meth:`end_episode` just closed, or
        None (then nothing travels): small and picklable (it crosses from env workers to the
        runner with the episode's metrics); never logged itself."""
        return None

    def merge(self, later: Evaluator) -> None:
        """Take in the episodes ``later`` (an evaluator of the same behaviour and protocol)
        recorded, as if this one had recorded them after its own.

        ``devlearn eval --envs N`` plays the evaluation's episodes in N environments at once,
        each with its own evaluator over a run of consecutive episodes (in worker processes
        too: evaluators travel pickled), then merges them in episode order. Afterwards
        :meth:`summary` and :meth:`write_artifacts` must be exactly what one evaluator that
        recorded every episode in order reports (``devlearn.testing.check_evaluator_merge``
        checks it). Neither evaluator has an episode open.

        Raises:
            NotImplementedError: The default, for an evaluator that is not :attr:`mergeable`.
        """
        raise NotImplementedError(f"{type(self).__name__} does not merge")


class RunMetrics:
    """Metrics over all of a run's finished training episodes (every env, worker and rank),
    kept by the runner: one instance per run, from ``Behavior.evaluation().run_metrics``.

    After each PPO iteration the runner passes the :meth:`Evaluator.episode_record` of every
    episode that ended in it (all ranks', in rank order) to :meth:`add`, and logs
    :meth:`values` as ``metrics/<name>`` in metrics.jsonl and TensorBoard. Its state is saved
    in checkpoints, so ``--resume`` and ``--from`` continue it.
    """

    def add(self, records: list[Any]) -> None:
        """Take note of finished episodes' records, oldest first."""

    def values(self) -> dict[str, float]:
        """The metrics now (name -> float); empty before any episode ended."""
        return {}

    def state_dict(self) -> dict[str, Any]:
        """The state a checkpoint keeps (picklable)."""
        return {}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore :meth:`state_dict`'s output."""
