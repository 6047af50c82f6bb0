"""The Behavior interface: what the infant should learn, independent of PPO and of the body."""

from __future__ import annotations

import inspect
import math
from abc import ABC, abstractmethod
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from devlearn.api.capabilities import About, Artifacts, EpisodeHooks, EpisodeSpec, EvalProtocol
from devlearn.api.curriculum import Curriculum, Stage
from devlearn.api.errors import UsageError
from devlearn.api.rewards import (
    BatchedIntrinsicReward,
    IntrinsicReward,
    StepContext,
    build_reward_terms,
    listed_term,
    reward_term_cfg,
)

if TYPE_CHECKING:
    from devlearn.api.network_spec import NetworkSpec
    from devlearn.infant import Infant


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
    kept by the runner: one instance per run, from :meth:`Behavior.run_metrics`.

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


_DERIVED_ABOUT: set[type] = set()


class Behavior(ABC):
    """What the infant should learn: scene, senses, observations, rewards, curriculum, metrics.

    A behaviour knows nothing of rsl-rl. It is constructed from its config dataclass
    (``config_class``) in every environment process, so it must be picklable and cheap.
    Plugins register Behavior subclasses through the ``register_behaviors`` hook.

    **The core** (:data:`BEHAVIOR_CORE`), what every behaviour writes: the class attributes
    ``name``, ``scene`` and ``config_class``, and six methods, two of them abstract:

    ================  ==========================================================================
    ``facts``         per-step facts shared by observations, rewards and metrics (default: none)
    ``observe``       the observations (abstract)
    ``network``       the policy and value networks (abstract)
    ``reward_terms``  the reward terms (default: those the config's ``rewards`` field declares)
    ``curriculum``    the training stages (default: one stage)
    ``evaluator``     the metrics collector (default: one that records nothing)
    ================  ==========================================================================

    **Optional capabilities** (:data:`BEHAVIOR_OPTIONAL`), each declared below with a default
    that does nothing special, in groups:

    ===================  =====================================================================
    ~episode             ``senses``, ``infant_options``, ``episode_seconds``,
                         ``on_episode_start``, ``before_step``, ``process_action``,
                         ``obs_groups``: the body a behaviour reads, how long an episode
                         lasts, and hooks around every reset and step
    batching             ``facts_every_physics_step``, ``batch_facts``, ``batch_observe``: how
                         facts are computed with a decision rate and over a worker's envs
    run settings         ``train_defaults``, ``run_length_defaults``, ``presets``,
                         ``paper_results``: run-config values as data, and the paper's figures
    ~evaluation          ``description``, ``headline_metric``, ``eval_stage``, ``eval_start``,
                         ``run_metrics``, ``render_frame``: what ``devlearn eval``, ``report``
                         and the progress bar show, and where evaluation episodes start
    ~artifacts           ``prepare``, ``policy_artifacts``, ``load_policy_artifacts``: one-off
                         work before training and what a policy file must carry
    ===================  =====================================================================

    Each environment owns its own copy of the behaviour and calls, per episode and step::

        reset:  infant.reset(rng) -> on_episode_start(infant, rng) -> facts -> observe
        step:   before_step(infant, action) -> process_action -> physics step -> facts
                -> observe -> reward terms -> evaluator.record
    """

    # --- the core: what every behaviour writes ------------------------------------------------
    name: ClassVar[str]
    """Unique name used on the command line (``devlearn run NAME``)."""

    scene: str
    """Infant scene to build: ``"crib"``, ``"sitting"`` or ``"sitting_babybench"``
    (:func:`devlearn.infant.build_infant`); an instance may set its own from its config."""

    config_class: ClassVar[type]
    """Dataclass of the behaviour's own options; every field documented. Overridable on the CLI
    as ``--set behavior.FIELD=VALUE``."""

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

    def facts(self, infant: Infant) -> dict[str, Any]:
        """Compute per-step facts shared by observations, rewards and metrics (once a step)."""
        return {}

    @abstractmethod
    def observe(self, infant: Infant, facts: dict[str, Any]) -> dict[str, np.ndarray]:
        """Return this step's observations, name -> float32 array of a fixed shape."""

    @abstractmethod
    def network(self) -> NetworkSpec:
        """Return how to build the policy and value networks."""

    def reward_terms(self) -> Sequence[IntrinsicReward | BatchedIntrinsicReward]:
        """Return fresh reward-term instances for one environment.

        Default: the terms the config declares in its ``rewards`` field (term name ->
        :class:`~devlearn.api.rewards.RewardTermCfg`: class, weight, params), built by
        :func:`~devlearn.api.rewards.build_reward_terms`, so that every term can be switched off
        or swept with ``--set behavior.rewards.NAME.weight=W``. Override it to add options of
        the behaviour's own to some terms (self_touch's ``lifetime_memory``) or to leave terms
        out. A :class:`~devlearn.api.rewards.BatchedIntrinsicReward` is computed once per
        worker over all its environments; a plain :class:`IntrinsicReward` runs in each
        environment (the core wraps it in :class:`~devlearn.api.rewards.BatchedFromPerEnv`).
        Both kinds may be mixed.

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

    def evaluator(self, training: bool) -> Evaluator:
        """Return a fresh metrics collector (``training=False`` for ``devlearn eval``)."""
        return Evaluator()

    # --- composed capabilities -------------------------------------------------------------
    about: ClassVar[About] = About()
    """What is known of this behaviour without building it (:class:`About`)."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        written = [k for k in cls.__mro__ if "about" in vars(k) and k not in _DERIVED_ABOUT]
        if written and written[0] is not Behavior:
            return
        _DERIVED_ABOUT.add(cls)
        # transition: the old members, read as an About
        plain = object.__new__(cls)
        cls.about = About(
            description=cls.description,
            headline_metric=cls.headline_metric,
            train_defaults=cls.train_defaults(plain),
            presets=cls.presets,
            run_length_defaults=lambda steps: cls.run_length_defaults(plain, steps),
            paper_results=cls.paper_results,
        )

    def episode(self) -> EpisodeSpec:
        """The body this behaviour reads and how its episodes go (:class:`EpisodeSpec`)."""
        return EpisodeSpec(
            senses=tuple(self.senses),
            infant_options=self.infant_options(),
            seconds=self.episode_seconds(),
            facts_every_physics_step=self.facts_every_physics_step,
            hooks=_BehaviorHooks(self),
        )

    def evaluation(self) -> EvalProtocol:
        """How episodes are scored and evaluated (:class:`EvalProtocol`)."""
        return EvalProtocol(
            evaluator=lambda training: self.evaluator(training),
            run_metrics=self.run_metrics(),
            stage=self.eval_stage(),
            start=self.eval_start(),
            render_frame=self.render_frame,
        )

    def artifacts(self) -> Artifacts:
        """One-off work before training and what a policy file carries (:class:`Artifacts`)."""
        return _BehaviorArtifacts(self)

    # --- optional: episode (the body read, hooks around resets and steps) ---------------------
    senses: ClassVar[tuple[str, ...]] = ("touch", "proprioception", "vestibular")
    """Infant senses read: ``touch``, ``proprioception``, ``vestibular``, ``eyes``."""

    def infant_options(self) -> dict[str, Any]:
        """Keyword arguments for :func:`devlearn.infant.build_infant` beyond the scene and
        senses, e.g. ``{"appearance": "skin"}``: how the infant looks, without building it."""
        return {}

    def episode_seconds(self) -> float | None:
        """Simulated seconds per episode (the environment converts them with the body's
        physics step; a whole number of decisions), or None (the default): the infant's own,
        BabyBench's 5 s. ``devlearn eval --session S`` overrides it for an evaluation."""
        return None

    def on_episode_start(self, infant: Infant, rng: np.random.Generator) -> None:
        """Called at the start of every episode, after the infant's reset, before its first
        :meth:`facts` (also in worker processes, and for the first episode of a new env).

        Use it to reset per-episode state kept on the behaviour (e.g. the previous eye frame of
        an optical-flow fact) and to read things from the infant once (actuator groups).

        Args:
            infant: The infant, already in the episode's initial pose.
            rng: The environment's generator (the one that drew the initial pose); draw from it
                for per-episode randomness so runs stay reproducible from the seed.
        """

    def before_step(self, infant: Infant, action: np.ndarray) -> None:
        """Called before every control step, with the policy's action clipped to [-1, 1],
        before :meth:`process_action` and the physics step.

        Args:
            infant: The infant before the step.
            action: (action_dim,) float64, read-only use (e.g. an action-cost fact).
        """

    def process_action(self, action: np.ndarray, stage: dict[str, Any]) -> np.ndarray:
        """Adjust a policy action before it reaches the body (e.g. zero an inactive arm).

        Args:
            action: (action_dim,) in [-1, 1].
            stage: The active stage's options.
        Returns:
            (action_dim,) array.
        """
        return action

    def obs_groups(self, observation_names: list[str]) -> dict[str, list[str]]:
        """Map rsl-rl's observation sets (``actor``, ``critic``) to observation names."""
        return {"actor": list(observation_names), "critic": list(observation_names)}

    # --- optional: batching -------------------------------------------------------------------
    facts_every_physics_step: ClassVar[bool] = True
    """With a decision rate (``env.action_repeat=K``, one action held for K physics steps):
    True (cheap facts, e.g. touch): facts, reward terms and the evaluator run at every physics
    step and the decision's reward is their sum, exactly an env stepped K times with the same
    action. False (facts that need renders, e.g. eye images and a detector): physics runs K
    times, then facts, observations, reward terms and the evaluator run once, on the state the
    decision reached, and the reward terms are paid K times (held over the decision)."""

    def batch_facts(self, infants: Sequence[Infant]) -> list[dict[str, Any]]:
        """:meth:`facts` of several environments at once, in their order.

        Override it (and :meth:`batch_observe`) when per-step Python cost matters: a worker
        then calls it once per step, on its first environment's behaviour, with all its
        infants. An override must return, for every infant, exactly what :meth:`facts` would
        (:func:`devlearn.testing.check_batched_observations` compares them), so it suits
        behaviours whose facts keep no per-environment state on ``self``. Without an
        override every environment calls its own behaviour's :meth:`facts`, as before.

        Args:
            infants: The environments' infants after this step's physics, (num_envs,).
        Returns:
            One facts dict per infant (default: ``[self.facts(i) for i in infants]``).
        """
        return [self.facts(infant) for infant in infants]

    def batch_observe(
        self, infants: Sequence[Infant], facts: Sequence[dict[str, Any]]
    ) -> dict[str, np.ndarray]:
        """:meth:`observe` of several environments at once, as arrays over them.

        Called like :meth:`batch_facts` (once per worker step, when overridden) with its
        result. Row ``i`` of every array must equal ``observe(infants[i], facts[i])``.

        Args:
            infants: The environments' infants, (num_envs,).
            facts: Their facts, as :meth:`batch_facts` returned them.
        Returns:
            Observation name -> (num_envs, *shape) array (default: :meth:`observe` per
            environment, stacked).
        """
        rows = [self.observe(infant, f) for infant, f in zip(infants, facts)]
        return {name: np.stack([row[name] for row in rows]) for name in rows[0]}

    # --- optional: run settings and the paper's figures ---------------------------------------
    def train_defaults(self) -> dict[str, Any]:
        """Run-config overrides this behaviour prefers, as dotted keys (``{"total_steps": 8e6}``).

        Returns:
            Mapping of dotted RunConfig keys to values.
        """
        return {}

    def run_length_defaults(self, total_steps: int) -> dict[str, Any]:
        """Run-config values that depend on the run's length (dotted keys), applied to a new
        run after ``--steps`` and ``--set`` for every key that neither ``--set`` nor the preset
        gave: e.g. stage lengths as shares of the run (hand regard: 10% left arm, 10% right
        arm, the rest both), so that a short run goes through every stage. Default: none.

        Args:
            total_steps: The run's ``total_steps``.
        """
        return {}

    presets: ClassVar[dict[str, dict[str, Any]]] = {}
    """Named sets of run-config overrides (data), chosen with ``devlearn run NAME --preset P``
    (e.g. ``{"paper": {"behavior.max_std": 0.0}}``: the paper's values one switch away from a
    default that differs): preset name -> dotted RunConfig keys -> values. Applied over
    :meth:`train_defaults` and under the command line's options and ``--set``; ``devlearn
    config NAME`` lists them. Default: none."""

    @classmethod
    def paper_results(cls, config: dict[str, Any]) -> tuple[str, dict[str, float]] | None:
        """The paper's figures a run with ``config`` (a saved config dict, as in an eval JSON)
        is compared with: a column of ``devlearn report`` beside ours and the baselines.

        Returns:
            ``(column label, {metric: value})`` with metric names as the eval JSON's keys
            (nested ones dotted, e.g. ``visibility.left_eye_left_hand``), or None.
        """
        return None

    # --- optional: evaluation and display -----------------------------------------------------
    description: ClassVar[str] = ""
    """One line shown by ``devlearn plugins`` and ``devlearn info``."""

    headline_metric: ClassVar[str] = ""
    """Key of :meth:`Evaluator.end_episode` shown on the progress bar."""

    def eval_stage(self) -> dict[str, Any] | None:
        """The stage options of ``devlearn eval``, when the behaviour declares its evaluation
        protocol (self-touch: random initial poses, the paper's sec. II-A6; hand regard: both
        arms from BabyBench's start).

        None (the default): evaluation starts where the policy trained, the curriculum stage
        of the checkpoint's training steps (a baseline: the stage a default run ends in), so
        that a policy is first judged on the skill it trained
        (:func:`evaluation_stage`). ``devlearn eval --start random|rest|babybench`` overrides
        the start either way, and the eval JSON records the start used."""
        return None

    def eval_start(self) -> str | None:
        """The infant start (:data:`devlearn.infant.starts.STARTS`: ``babybench``, ``rest``)
        ``devlearn eval`` plays episodes from when the evaluation stage does not randomise
        the pose, e.g. hand regard's ``babybench``, BabyBench's start.

        None (the default): the infant's own start, where the policy trained.
        ``devlearn eval --start`` overrides it."""
        return None

    def run_metrics(self) -> RunMetrics | None:
        """Return the run-wide metrics over finished training episodes (:class:`RunMetrics`),
        or None (the default) when the behaviour keeps none."""
        return None

    def render_frame(self, infant: Infant) -> np.ndarray:
        """One frame of ``devlearn eval --video``, (H, W, 3) uint8.

        Default: the scene's third-person view (``infant.render_view()``); override to add
        what this behaviour attends to (hand regard puts both eyes' views beside it).
        """
        return infant.render_view()

    # --- optional: artifacts ------------------------------------------------------------------
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


BEHAVIOR_CORE: tuple[str, ...] = (
    "name",
    "scene",
    "config_class",
    "facts",
    "observe",
    "network",
    "reward_terms",
    "curriculum",
    "evaluator",
)
"""What every behaviour writes: three class attributes and six methods (:class:`Behavior`'s
table); ``devlearn new`` writes them first."""

BEHAVIOR_OPTIONAL: dict[str, tuple[str, ...]] = {
    "episode": (
        "senses",
        "infant_options",
        "episode_seconds",
        "on_episode_start",
        "before_step",
        "process_action",
        "obs_groups",
    ),
    "batching": ("facts_every_physics_step", "batch_facts", "batch_observe"),
    "run settings": ("train_defaults", "run_length_defaults", "presets", "paper_results"),
    "evaluation": (
        "description",
        "headline_metric",
        "eval_stage",
        "eval_start",
        "run_metrics",
        "render_frame",
    ),
    "artifacts": ("prepare", "policy_artifacts", "load_policy_artifacts"),
    "composed": ("about", "episode", "evaluation", "artifacts"),
}
"""The optional capabilities of :class:`Behavior` by group, each declared there with a default;
together with :data:`BEHAVIOR_CORE` every public member of the contract, once."""


class _BehaviorHooks(EpisodeHooks):
    def __init__(self, behavior: Behavior) -> None:
        self.behavior = behavior

    def on_episode_start(self, infant: Infant, rng: np.random.Generator) -> None:
        self.behavior.on_episode_start(infant, rng)

    def before_step(self, infant: Infant, action: np.ndarray) -> None:
        self.behavior.before_step(infant, action)

    def process_action(self, action: np.ndarray, stage: dict[str, Any]) -> np.ndarray:
        return self.behavior.process_action(action, stage)


class _BehaviorArtifacts(Artifacts):
    def __init__(self, behavior: Behavior) -> None:
        self.behavior = behavior

    def prepare(self, run_dir: Path) -> None:
        self.behavior.prepare(run_dir)

    def policy_artifacts(self) -> dict[str, Any]:
        return self.behavior.policy_artifacts()

    def load_policy_artifacts(self, artifacts: dict[str, Any], folder: Path) -> None:
        self.behavior.load_policy_artifacts(artifacts, folder)


def evaluation_stage(behavior: Behavior, trained_steps: int) -> dict[str, Any]:
    """The stage options ``devlearn eval`` (and the conformance kit) evaluate ``behavior``
    under: its declared :meth:`Behavior.eval_stage`, or else the options of its curriculum's
    stage at ``trained_steps`` (where a policy trained for that many steps ended its training).
    """
    declared = behavior.evaluation().stage
    if declared is not None:
        return dict(declared)
    curriculum = behavior.curriculum()
    return dict(curriculum.stages[curriculum.stage_index_at(int(trained_steps))].options)
