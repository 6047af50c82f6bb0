"""The optional capabilities a :class:`~devlearn.api.behavior.Behavior` composes: small objects,
each returned by one member of the behaviour, whose defaults do nothing special.

- :class:`About` (the class attribute ``about``): what is known of a behaviour without building
  it: its description, headline metric, run-config defaults, presets and the paper's figures.
- :class:`EpisodeSpec` (``episode()``): the body a behaviour reads (senses, infant options), how
  long an episode lasts, when facts run under a decision rate, and its :class:`EpisodeHooks`.
- :class:`EvalProtocol` (``evaluation()``): how episodes are scored and evaluated: the
  evaluator, the run-wide metrics, the evaluation stage and start, the video frame.
- :class:`Artifacts` (``artifacts()``): one-off work before training and what a policy file
  must carry to be evaluated anywhere.

The core reads these objects; it never checks which methods a behaviour overrides.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from devlearn.api.evaluator import Evaluator

if TYPE_CHECKING:
    from devlearn.api.evaluator import RunMetrics
    from devlearn.infant import Infant


@dataclass(frozen=True)
class About:
    """What is known of a behaviour without building it: read from its class (the class
    attribute ``Behavior.about``) by ``devlearn plugins``, ``config``, ``run``, ``report`` and
    config resolution.

    Attributes:
        description: One line shown by ``devlearn plugins`` and ``devlearn info``.
        headline_metric: Key of :meth:`Evaluator.end_episode` shown on the progress bar and
            in reports ("" for none).
        train_defaults: Run-config overrides this behaviour prefers, dotted keys -> values
            (``{"total_steps": 8e6}``), applied over the core's defaults.
        presets: Named sets of run-config overrides chosen with ``devlearn run NAME --preset
            P`` (e.g. ``{"paper": {"behavior.max_std": 0.0}}``): preset name -> dotted keys ->
            values, applied over :attr:`train_defaults` and under the command line's options
            and ``--set``; ``devlearn config NAME`` lists them.
        run_length_defaults: ``f(total_steps) -> {dotted key: value}``: run-config values that
            depend on the run's length, applied to a new run after ``--steps`` and ``--set``
            for every key neither ``--set`` nor the preset gave (e.g. stage lengths as shares
            of the run, so that a short run goes through every stage); None: none.
        paper_results: ``f(saved config dict) -> (column label, {metric: value}) | None``: the
            paper's figures a run with that config is compared with in ``devlearn report``
            (metric names as the eval JSON's keys, nested ones dotted); None: none.
    """

    description: str = ""
    headline_metric: str = ""
    train_defaults: dict[str, Any] = field(default_factory=dict)
    presets: dict[str, dict[str, Any]] = field(default_factory=dict)
    run_length_defaults: Callable[[int], dict[str, Any]] | None = None
    paper_results: Callable[[dict[str, Any]], tuple[str, dict[str, float]] | None] | None = None

    def length_defaults(self, total_steps: int) -> dict[str, Any]:
        """:attr:`run_length_defaults` for a run of ``total_steps`` (empty without one)."""
        if self.run_length_defaults is None:
            return {}
        return dict(self.run_length_defaults(int(total_steps)))

    def paper_figures(self, config: dict[str, Any]) -> tuple[str, dict[str, float]] | None:
        """:attr:`paper_results` for a run with ``config`` (None without them)."""
        return None if self.paper_results is None else self.paper_results(config)


class EpisodeHooks:
    """Hooks around every reset and step of one environment (the defaults do nothing).

    Each environment owns its behaviour and so its hooks: state kept here (the previous eye
    frame, an arm mask) is that environment's, and a behaviour's per-environment facts
    (:func:`~devlearn.api.batching.per_env`) may read it. Per episode and step::

        reset:  infant.reset(rng) -> on_episode_start(infant, rng) -> facts -> observe
        step:   before_step(infant, action) -> process_action -> physics step -> facts
                -> observe -> reward terms -> evaluator.record
    """

    def on_episode_start(self, infant: Infant, rng: np.random.Generator) -> None:
        """Called at the start of every episode, after the infant's reset, before its first
        facts (also in worker processes, and for the first episode of a new env).

        Args:
            infant: The infant, already in the episode's initial pose.
            rng: The environment's generator (the one that drew the initial pose); draw from it
                for per-episode randomness so runs stay reproducible from the seed.
        """

    def before_step(self, infant: Infant, action: np.ndarray) -> None:
        """Called before every physics step with the action clipped to [-1, 1], before
        :meth:`process_action`.

        Args:
            infant: The infant before the step.
            action: (action_dim,) float64, read-only use (e.g. an action-cost fact).
        """

    def process_action(self, action: np.ndarray, stage: dict[str, Any]) -> np.ndarray:
        """Adjust an action before it reaches the body (e.g. zero an inactive arm).

        Args:
            action: (action_dim,) in [-1, 1].
            stage: The active curriculum stage's options.
        Returns:
            (action_dim,) array.
        """
        return action


@dataclass(frozen=True)
class EpisodeSpec:
    """The body a behaviour reads and how its episodes go (``Behavior.episode()``).

    Attributes:
        senses: Infant senses read: ``touch``, ``proprioception``, ``vestibular``, ``eyes``.
        infant_options: Keyword arguments for :func:`devlearn.infant.build_infant` beyond the
            scene and senses, e.g. ``{"appearance": "skin"}``.
        seconds: Simulated seconds per episode (a whole number of decisions), or None: the
            infant's own, BabyBench's 5 s. ``devlearn eval --session S`` overrides it.
        facts_every_physics_step: With a decision rate (``env.action_repeat=K``): True (cheap
            facts, e.g. touch): facts, reward terms and the evaluator run at every physics step
            and the decision's reward is their sum, exactly an env stepped K times with the
            same action (observations inside the decision are computed only where a term or
            the evaluator reads them: the policy sees the last step's). False (facts that
            render, e.g. eye images and a detector): physics
            runs K times, then facts, observations, terms and the evaluator run once on the
            state the decision reached, and the terms are paid K times.
        hooks: The environment's :class:`EpisodeHooks` (default: none). Return the same object
            from every ``episode()`` call of one behaviour when it keeps state.
    """

    senses: tuple[str, ...] = ("touch", "proprioception", "vestibular")
    infant_options: Mapping[str, Any] = field(default_factory=dict)
    seconds: float | None = None
    facts_every_physics_step: bool = True
    hooks: EpisodeHooks = field(default_factory=EpisodeHooks)


def _no_metrics(training: bool) -> Evaluator:
    return Evaluator()


@dataclass(frozen=True)
class EvalProtocol:
    """How a behaviour's episodes are scored and evaluated (``Behavior.evaluation()``).

    Attributes:
        evaluator: ``f(training) -> Evaluator``: a fresh metrics collector
            (``training=False`` for ``devlearn eval``); default: one that records nothing.
        run_metrics: The run-wide metrics over finished training episodes (a fresh
            :class:`~devlearn.api.behavior.RunMetrics` with every ``evaluation()`` call), or
            None when the behaviour keeps none.
        stage: The stage options of ``devlearn eval`` when the behaviour declares its
            evaluation protocol (self-touch: random initial poses); None: evaluation starts
            where the policy trained, the curriculum stage of the checkpoint's training steps
            (:func:`~devlearn.api.behavior.evaluation_stage`). ``devlearn eval --start``
            overrides the start either way.
        start: The infant start (:data:`devlearn.infant.starts.STARTS`) ``devlearn eval`` plays
            episodes from when the stage does not randomise the pose (hand regard:
            ``babybench``); None: the infant's own start, where the policy trained.
        render_frame: ``f(infant) -> (H, W, 3) uint8``, one frame of ``devlearn eval
            --video``; None: the scene's third-person view (``infant.render_view()``).
    """

    evaluator: Callable[[bool], Evaluator] = _no_metrics
    run_metrics: RunMetrics | None = None
    stage: Mapping[str, Any] | None = None
    start: str | None = None
    render_frame: Callable[[Infant], np.ndarray] | None = None

    def frame(self, infant: Infant) -> np.ndarray:
        """One video frame of ``infant``: :attr:`render_frame`'s, or its third-person view."""
        if self.render_frame is None:
            return infant.render_view()
        return self.render_frame(infant)


class Artifacts:
    """One-off work before training, and what a policy file must carry besides its weights
    (``Behavior.artifacts()``; the defaults do nothing, e.g. hand regard's calibrated detector)."""

    def prepare(self, run_dir: Path) -> None:
        """One-off work before training (e.g. motor babbling); may update the behaviour's
        config. Called in the main process once per run, before environments are built; on
        resume it is called again and should reuse what it saved in ``run_dir``."""

    def policy_artifacts(self) -> dict[str, Any]:
        """Data evaluation needs besides the policy weights, stored in policy files
        (``devlearn slim``) so that they evaluate anywhere: plain dicts, lists, numbers and
        strings only (checkpoints load with ``weights_only``)."""
        return {}

    def load_policy_artifacts(self, artifacts: dict[str, Any], folder: Path) -> None:
        """Get ready to evaluate a checkpoint: restore :meth:`policy_artifacts`' output.

        Args:
            artifacts: What the checkpoint stored (empty for a training checkpoint).
            folder: The checkpoint's folder; files the config names resolve against it when
                they are not where the config says (a copied or relocated run folder).
        Raises:
            UsageError: Something evaluation needs is neither stored nor found.
        """
