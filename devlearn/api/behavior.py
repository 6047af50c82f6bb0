"""The Behavior interface: what the infant should learn, independent of PPO and of the body."""

from __future__ import annotations

import inspect
import math
from abc import ABC, abstractmethod
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from devlearn.api.batching import EnvBatch
from devlearn.api.capabilities import About, Artifacts, EpisodeSpec, EvalProtocol
from devlearn.api.curriculum import Curriculum, Stage
from devlearn.api.errors import UsageError
from devlearn.api.evaluator import Evaluator as Evaluator  # re-exported: its old home
from devlearn.api.evaluator import RunMetrics as RunMetrics
from devlearn.api.rewards import (
    BatchedIntrinsicReward,
    IntrinsicReward,
    build_reward_terms,
    listed_term,
    reward_term_cfg,
)

if TYPE_CHECKING:
    from devlearn.api.network_spec import NetworkSpec


WEIGHT_MAX = 1e6
"""Largest magnitude of a reward term's weight (a larger one times a term's value overflows or
drowns every other term; rewards are normalised anyway)."""


class BehaviorConfig:
    """A base for a behaviour's config dataclass (its ``config_class``) that declares what the
    core reads of it besides the fields: a check of the values, and the values old runs were
    trained with. Optional: a plain dataclass works as a config and gets neither.

    The fields are the behaviour's options (``--set behavior.FIELD=VALUE``, each documented);
    a ``rewards`` field of term name -> :class:`~devlearn.api.rewards.RewardTermCfg` declares
    the reward terms (:meth:`Behavior.reward_terms`).
    """

    LEGACY_DEFAULTS: ClassVar[dict[str, Any]] = {}
    """Field -> the value a saved config (a run's config.json, a checkpoint's config) that
    lacks the field was trained with: a field added, or whose default changed, after runs were
    saved. Such a config loads, resumes and evaluates as trained
    (:func:`devlearn.config.run_config.from_dict`); a new run takes the field's default."""

    LEGACY_REWARD_KEYS: ClassVar[dict[str, str]] = {}
    """Old field -> where its value now lives in the ``rewards`` table (``TERM.weight`` or
    ``TERM.params.NAME``), for fields moved there after runs were saved: a saved config that
    still has them loads with the values moved
    (:func:`devlearn.api.rewards.upgrade_saved_rewards`)."""

    def validate(self) -> None:
        """Check the values; called whenever a :class:`Behavior` is built on this config
        (``--set`` assigns fields after the dataclass was made, so ``__post_init__`` alone
        would miss them). Default: nothing to check.

        Raises:
            ValueError: A wrong value, named with the valid ones (one line).
        """


def declared_terms(config: Any) -> list[str]:
    """The reward-term classes a behaviour config's ``rewards`` table may name: those its
    config class's defaults declare (``type(config)().rewards``; a term such a table leaves
    unpaid is declared with weight 0, as hand regard's ``reach_into_view``), each one a
    listed term (:func:`~devlearn.api.rewards.registered_terms`). Another behaviour's term
    reads facts this behaviour never computes, and a private or abstract class is no term:
    neither fits.

    Returns:
        Class paths ``module:QualName``, sorted (empty for a config without ``rewards``).
    """
    defaults = getattr(type(config)(), "rewards", None) or {}
    paths = {str(reward_term_cfg(term).cls) for term in defaults.values()}
    return sorted(path for path in paths if listed_term(path) is not None)


def check_reward_table(config: Any) -> None:
    """Refuse a behaviour config whose ``rewards`` table names a class its behaviour does not
    declare (:func:`declared_terms`: resolved by name among the registered terms, never
    imported: a config or checkpoint is data), a weight out of bounds or a parameter the class
    does not take. Every :class:`Behavior` checks its config so when built, and so does every
    saved config read (:func:`devlearn.config.run_config.from_dict`: ``--config``, ``--resume``,
    a checkpoint's config, the Gymnasium envs' overrides): the one check of a reward table.

    Raises:
        UsageError: naming the ``behavior.rewards...`` key and what is valid.
    """
    table = getattr(config, "rewards", None) or {}
    valid = declared_terms(config) if table else []
    for name, term in table.items():
        term = reward_term_cfg(term)
        if str(term.cls) not in valid:
            shown = repr(term.cls) if len(repr(term.cls)) <= 80 else repr(term.cls)[:77] + "..."
            raise UsageError(
                f"behavior.rewards.{name}.cls: unknown reward term class {shown}: a config "
                "names only the reward terms its behaviour declares; valid: "
                f"{', '.join(valid) or 'none'}"
            )
        cls = term.term_class()
        if not (math.isfinite(term.weight) and abs(term.weight) <= WEIGHT_MAX):
            raise UsageError(
                f"behavior.rewards.{name}.weight must be a finite number from -{WEIGHT_MAX:g} "
                f"to {WEIGHT_MAX:g}, got {term.weight:g}"
            )
        accepted = inspect.signature(cls).parameters
        if not any(p.kind is p.VAR_KEYWORD for p in accepted.values()):
            valid_params = sorted(k for k in accepted if k not in ("self", "weight"))
            for param in term.params:
                if param not in accepted or param == "weight":
                    raise UsageError(
                        f"unknown parameter 'behavior.rewards.{name}.params.{param}' of "
                        f"{cls.__name__}; valid: {', '.join(valid_params) or 'none'}"
                    )


class Behavior(ABC):
    """What the infant should learn: scene, senses, observations, rewards, curriculum, metrics.

    A behaviour knows nothing of rsl-rl. It is constructed from its config dataclass
    (``config_class``) in every environment process, so it must be picklable and cheap; each
    environment owns its own instance (``self.config`` is the config it was built on). Plugins
    register Behavior subclasses through the ``register_behaviors`` hook.

    The whole contract is these twelve members; a behaviour writes ``name``, ``scene``,
    ``config_class``, ``observe`` and ``network`` and whichever others it needs:

    ==================  =========================================================================
    ``name``            the name on the command line (``devlearn run NAME``)
    ``scene``           the infant's scene
    ``config_class``    the dataclass of its options (``--set behavior.FIELD=VALUE``)
    ``about``           what is known without building it (:class:`About`: description,
                        headline metric, run-config defaults, presets, the paper's figures)
    ``facts``           per-step facts of a batch of environments, shared by observations,
                        rewards and metrics (default: none)
    ``observe``         the observations of a batch of environments (abstract)
    ``network``         the policy and value networks, and what actor and critic see (abstract)
    ``reward_terms``    the reward terms (default: those the config's ``rewards`` declares)
    ``curriculum``      the training stages (default: one stage)
    ``episode``         the body read and the episode (:class:`EpisodeSpec`: senses, infant
                        options, length, facts under a decision rate, :class:`EpisodeHooks`)
    ``evaluation``      how episodes are scored (:class:`EvalProtocol`: the evaluator, run
                        metrics, the evaluation's stage and start, the video frame)
    ``artifacts``       one-off work before training and what a policy file carries
                        (:class:`Artifacts`)
    ==================  =========================================================================

    Facts, observations and reward terms have one batched form, which the core calls once per
    step for a worker's environments (:class:`~devlearn.api.batching.EnvBatch`). An author who
    prefers to write facts and observations for one environment decorates them with
    :func:`~devlearn.api.batching.per_env`; a reward term for one environment is an
    :class:`~devlearn.api.rewards.IntrinsicReward` (the core wraps it in
    :class:`~devlearn.api.rewards.BatchedFromPerEnv`). Per environment and step::

        reset:  infant.reset(rng) -> hooks.on_episode_start(infant, rng) -> facts -> observe
        step:   hooks.before_step(infant, action) -> hooks.process_action -> physics step
                -> facts -> observe -> reward terms -> evaluator.record
    """

    name: ClassVar[str]
    """Unique name used on the command line (``devlearn run NAME``)."""

    scene: str
    """Infant scene to build: ``"crib"``, ``"sitting"`` or ``"sitting_babybench"``
    (:func:`devlearn.infant.build_infant`); an instance may set its own from its config."""

    config_class: ClassVar[type]
    """Dataclass of the behaviour's own options; every field documented. Overridable on the CLI
    as ``--set behavior.FIELD=VALUE``."""

    about: ClassVar[About] = About()
    """What is known of this behaviour without building it (:class:`About`), read from the
    class by ``devlearn plugins``, ``config``, ``run``, ``report`` and config resolution."""

    def __init__(self, config: Any | None = None) -> None:
        """Build on ``config`` (the config class's defaults when None), checked: its
        :meth:`BehaviorConfig.validate` and its reward table (:func:`check_reward_table`).

        Raises:
            ValueError: A value the config's ``validate`` refuses.
            UsageError: A reward term that names no registered class, a weight out of bounds
                or a parameter its class does not take.
        """
        self.config = config if config is not None else self.config_class()
        if isinstance(self.config, BehaviorConfig):
            self.config.validate()
        check_reward_table(self.config)

    def facts(self, batch: EnvBatch) -> list[dict[str, Any]]:
        """Per-step facts shared by observations, rewards and metrics (computed once a step).

        Args:
            batch: The environments after this step's physics (or one after its reset).
        Returns:
            One facts dict per environment, in batch order (default: empty ones). Row ``i``
            depends on environment ``i`` alone: a batch gives what each environment alone
            would (``devlearn.testing.check_batched_observations`` checks it).
        """
        return [{} for _ in range(len(batch))]

    @abstractmethod
    def observe(self, batch: EnvBatch, facts: Sequence[dict[str, Any]]) -> dict[str, np.ndarray]:
        """This step's observations of every environment in ``batch``.

        Called at every step the policy observes: each decision's last physics step (and each
        reset). Inside a decision (``env.action_repeat`` > 1 with
        ``EpisodeSpec.facts_every_physics_step``) it is called only where a reward term or the
        evaluator reads ``StepContext.observations``; so keep it free of side effects (state
        that must advance every physics step belongs in :meth:`facts`).

        Args:
            batch: The environments, as :meth:`facts` got them.
            facts: Their facts, as :meth:`facts` returned them.
        Returns:
            Observation name -> (num_envs, *shape) float32 (or uint8 image) array, a fixed
            shape per name.
        """

    @abstractmethod
    def network(self) -> NetworkSpec:
        """Return how to build the policy and value networks (and which observations the actor
        and the critic see: :attr:`NetworkSpec.actor`, :attr:`NetworkSpec.critic`)."""

    def reward_terms(self) -> Sequence[IntrinsicReward | BatchedIntrinsicReward]:
        """Return fresh reward-term instances for one environment.

        Default: the terms the config declares in its ``rewards`` field (term name ->
        :class:`~devlearn.api.rewards.RewardTermCfg`: class, weight, params), built by
        :func:`~devlearn.api.rewards.build_reward_terms`, so that every term can be switched off
        or swept with ``--set behavior.rewards.NAME.weight=W``. Override it to add options of
        the behaviour's own to some terms (self_touch's ``lifetime_memory``) or to leave terms
        out. A :class:`~devlearn.api.rewards.BatchedIntrinsicReward` is computed once per
        worker over all its environments; a per-environment
        :class:`~devlearn.api.rewards.IntrinsicReward` is wrapped by the core (in one place)
        into that form. Both kinds may be mixed.

        Raises:
            TypeError: The config has no ``rewards`` field and the behaviour does not override
                this method.
        """
        rewards = getattr(self.config, "rewards", None)
        if rewards is None:
            raise TypeError(
                f"{type(self).__name__}: declare the reward terms in the config's `rewards` "
                "field (name -> RewardTermCfg(class, weight, params)) or override reward_terms()"
            )
        return build_reward_terms(rewards)

    def curriculum(self) -> Curriculum:
        """Return the training curriculum (default: one stage, fixed initial pose)."""
        return Curriculum([Stage("main", None, {})])

    def episode(self) -> EpisodeSpec:
        """The body this behaviour reads and how its episodes go (:class:`EpisodeSpec`).
        Each environment reads it once, when it is built. Default: touch, proprioception and
        the vestibular sense, the infant's own episode length, no hooks."""
        return EpisodeSpec()

    def evaluation(self) -> EvalProtocol:
        """How this behaviour's episodes are scored and evaluated (:class:`EvalProtocol`).
        Default: an evaluator that records nothing, no run metrics, evaluation where the policy
        trained."""
        return EvalProtocol()

    def artifacts(self) -> Artifacts:
        """One-off work before training and what a policy file carries besides its weights
        (:class:`Artifacts`). Default: none."""
        return Artifacts()


def evaluation_stage(behavior: Behavior, trained_steps: int) -> dict[str, Any]:
    """The stage options ``devlearn eval`` (and the conformance kit) evaluate ``behavior``
    under: its declared ``evaluation().stage`` (:class:`EvalProtocol`), or else the options of
    its curriculum's stage at ``trained_steps`` (where a policy trained for that many steps ended
    its training).
    """
    declared = behavior.evaluation().stage
    if declared is not None:
        return dict(declared)
    curriculum = behavior.curriculum()
    return dict(curriculum.stages[curriculum.stage_index_at(int(trained_steps))].options)
