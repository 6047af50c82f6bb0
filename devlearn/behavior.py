"""The Behavior interface: what the infant should learn, independent of PPO and of the body."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from devlearn.curriculum import Curriculum, Stage
from devlearn.rewards import IntrinsicReward, StepContext
from devlearn.sensors import SensorEncoder

if TYPE_CHECKING:
    from devlearn.infant import Infant


@dataclass
class NetworkSpec:
    """How to assemble the policy and value networks from per-sense encoders.

    Both networks get their own copy of every encoder (no shared parameters). Each observation
    named in ``encoders`` goes through its encoder; the features are concatenated, passed
    through ``fusion_dims`` (Linear+ReLU each), then ``trunk_dims`` (Linear+ReLU each). The
    policy head is a Gaussian with ``tanh`` mean and state-dependent ``softplus`` standard
    deviation (paper, sec. II-A4); the value head is one linear layer.

    Attributes:
        encoders: Observation name -> encoder. Every observation in the behaviour's actor and
            critic groups must have one.
        fusion_dims: Fusion layers after concatenation (paper Model I: ``(512,)``).
        trunk_dims: Shared trunk layers before the heads (paper Model I: ``(256, 256)``).
        init_std: Initial standard deviation of the policy (softplus bias is set to match).
        max_std: Upper bound on the policy's standard deviation (a sigmoid replaces the
            softplus); 0: unbounded, as in the paper.
        normalize: Observations standardised by a running mean and variance before their
            encoder (rsl-rl's ``EmpiricalNormalization``, updated during rollouts), e.g.
            ``("proprioception",)`` whose joint velocities and torques have mixed scales.
    """

    encoders: dict[str, SensorEncoder]
    fusion_dims: tuple[int, ...] = (512,)
    trunk_dims: tuple[int, ...] = (256, 256)
    init_std: float = 0.5
    max_std: float = 0.0
    normalize: tuple[str, ...] = ()


class Evaluator:
    """Collects a behaviour's metrics over steps and episodes.

    The environment keeps one per sub-environment during training (each episode's
    :meth:`end_episode` metrics are logged under ``metrics/<key>``); ``devlearn eval`` keeps one
    over all evaluation episodes and prints :meth:`summary`.
    """

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


class Behavior(ABC):
    """What the infant should learn: scene, senses, observations, rewards, curriculum, metrics.

    A behaviour knows nothing of rsl-rl. It is constructed from its config dataclass
    (``config_class``) in every environment process, so it must be picklable and cheap.
    Plugins register Behavior subclasses through the ``register_behaviors`` hook.
    """

    name: ClassVar[str]
    """Unique name used on the command line (``devlearn run NAME``)."""
    description: ClassVar[str] = ""
    """One line shown by ``devlearn plugins`` and ``devlearn info``."""
    scene: ClassVar[str]
    """Infant scene to build: ``"crib"`` or ``"sitting"`` (:func:`devlearn.infant.build_infant`)."""
    senses: ClassVar[tuple[str, ...]] = ("touch", "proprioception", "vestibular")
    """Infant senses read: ``touch``, ``proprioception``, ``vestibular``, ``eyes``."""
    config_class: ClassVar[type]
    """Dataclass of the behaviour's own options; every field documented. Overridable on the CLI
    as ``--set behavior.FIELD=VALUE``."""
    headline_metric: ClassVar[str] = ""
    """Key of :meth:`Evaluator.end_episode` shown on the progress bar."""

    def __init__(self, config: Any | None = None) -> None:
        self.config = config if config is not None else self.config_class()

    # --- observations -------------------------------------------------------------------
    def facts(self, infant: Infant) -> dict[str, Any]:
        """Compute per-step facts shared by observations, rewards and metrics (once a step)."""
        return {}

    @abstractmethod
    def observe(self, infant: Infant, facts: dict[str, Any]) -> dict[str, np.ndarray]:
        """Return this step's observations, name -> float32 array of a fixed shape."""

    def obs_groups(self, observation_names: list[str]) -> dict[str, list[str]]:
        """Map rsl-rl's observation sets (``actor``, ``critic``) to observation names."""
        return {"actor": list(observation_names), "critic": list(observation_names)}

    @abstractmethod
    def network(self) -> NetworkSpec:
        """Return how to build the policy and value networks."""

    # --- rewards, actions, curriculum ----------------------------------------------------
    @abstractmethod
    def reward_terms(self) -> list[IntrinsicReward]:
        """Return fresh reward-term instances for one environment."""

    def curriculum(self) -> Curriculum:
        """Return the training curriculum (default: one stage, fixed initial pose)."""
        return Curriculum([Stage("main", None, {})])

    def eval_stage(self) -> dict[str, Any]:
        """Stage options used by ``devlearn eval`` (default: the curriculum's last stage)."""
        return dict(self.curriculum().stages[-1].options)

    def process_action(self, action: np.ndarray, stage: dict[str, Any]) -> np.ndarray:
        """Adjust a policy action before it reaches the body (e.g. zero an inactive arm).

        Args:
            action: (action_dim,) in [-1, 1].
            stage: The active stage's options.
        Returns:
            (action_dim,) array.
        """
        return action

    # --- metrics and set-up --------------------------------------------------------------
    def evaluator(self, training: bool) -> Evaluator:
        """Return a fresh metrics collector (``training=False`` for ``devlearn eval``)."""
        return Evaluator()

    def train_defaults(self) -> dict[str, Any]:
        """Run-config overrides this behaviour prefers, as dotted keys (``{"total_steps": 8e6}``).

        Returns:
            Mapping of dotted RunConfig keys to values.
        """
        return {}

    def prepare(self, run_dir: Path) -> None:
        """One-off work before training (e.g. motor babbling); may update ``self.config``.

        Called in the main process once per run, before environments are built; on resume
        it is called again and should reuse what it saved in ``run_dir``.
        """

    def policy_artifacts(self) -> dict[str, Any]:
        """Data evaluation needs besides the policy weights (e.g. a calibrated detector).

        Stored in policy files (``devlearn slim``) so that they evaluate anywhere; plain
        dicts, lists, numbers and strings only (checkpoints load with ``weights_only``).
        """
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

    def render_frame(self, infant: Infant) -> np.ndarray:
        """One frame of ``devlearn eval --video``, (H, W, 3) uint8.

        Default: the scene's third-person view (``infant.render_view()``); override to add
        what this behaviour attends to (hand regard puts both eyes' views beside it).
        """
        return infant.render_view()
