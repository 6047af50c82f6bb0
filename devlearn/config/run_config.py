"""Run configuration: the nested dataclasses, saved configs (:func:`to_dict`, :func:`from_dict`),
the learner's checks and rsl-rl's train_cfg. A run's config is built by
:func:`devlearn.config.resolve.resolve_run` (``--set`` overrides: :mod:`devlearn.config.values`)."""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from devlearn.api.behavior import BehaviorConfig, check_reward_table
from devlearn.api.errors import UsageError
from devlearn.api.rewards import upgrade_saved_rewards
from devlearn.config.values import convert, field_types
from devlearn.timing import PHYSICS_TIMESTEP

if TYPE_CHECKING:
    from devlearn.api.behavior import Behavior


@dataclass
class PPOConfig:
    """PPO hyper-parameters (rsl-rl's ``PPO`` keyword arguments plus the rollout length)."""

    learning_rate: float = 3e-4
    """Adam step size (the starting value when ``schedule`` is ``adaptive``) of a run of up to
    ``full_rate_steps``; a longer run takes less (:meth:`run_rate`)."""
    num_steps_per_env: int = 64
    """Steps each environment collects per iteration (rollout length)."""
    num_learning_epochs: int = 5
    """Passes over each rollout."""
    num_mini_batches: int = 4
    """Mini-batches per pass."""
    clip_param: float = 0.2
    """PPO ratio clip epsilon (paper, sec. II-A5: 0.2); also clips the value loss."""
    gamma: float = 0.99
    """Discount factor."""
    lam: float = 0.95
    """GAE lambda."""
    entropy_coef: float = 0.005
    """Weight of the entropy bonus."""
    value_loss_coef: float = 1.0
    """Weight of the value loss."""
    max_grad_norm: float = 1.0
    """Gradient-norm clip (actor and critic separately)."""
    desired_kl: float | None = 0.01
    """Target KL for the adaptive schedule (None disables adaptation)."""
    schedule: str = "fixed"
    """Learning-rate schedule: ``fixed`` (the default, :data:`LEARNER_EVIDENCE`: the adaptive
    schedule sat at its 1e-5 floor in issue #28's pilots), ``adaptive`` (KL-driven, rsl-rl's;
    ``desired_kl`` is its target) or ``linear`` (from ``learning_rate`` at the run's first step
    down to 0 at its last, by the run's share of steps done, cleanrl's ``anneal_lr``). Linear
    helps a run whose skill is learned early and refined late (self-touch at 2M, fixed poses:
    0.692 against the fixed step size's 0.588 and SB3's PPO's 0.603) and starves one whose
    skill emerges late, when the step size is small (both plugins at issue #38's 0.5M: the mean
    action 0.13 against 0.84 and 12 regions against 28.5); the default self-touch run (1M, both
    stages) scored lower on average too (0.532 against 0.622, 3 seeds), so it is not the
    default (issue #54, :data:`LEARNER_EVIDENCE`). A saved config without this field means
    ``adaptive``."""
    decay_share: float = 1.0
    """The share of the run, at its end, over which ``schedule=linear`` falls to 0: 1 (the
    default) falls over the whole run (cleanrl's); 0.2 holds ``learning_rate`` for the first 80%
    of the steps and falls over the last 20% (the "warmup-stable-decay" shape). Only read with
    ``schedule=linear``; from 0 (excluded) to 1. 0.2 kept about a third of the whole-run
    schedule's gain on self-touch at 2M (0.630 against the fixed step size's 0.588, paired
    +0.027 [-0.028, +0.081], 5 seeds), changed nothing in the default run (-0.004) and still
    made both plugins worse (issue #54, :data:`LEARNER_EVIDENCE`)."""
    full_rate_steps: int = 1_024_000
    """The longest run that takes ``learning_rate`` as it is; a longer run of ``total_steps``
    takes ``learning_rate * full_rate_steps / total_steps``, at least half ``learning_rate``
    (:data:`MIN_RATE_SHARE`, reached at twice ``full_rate_steps``), so that its step sizes sum
    to a ``full_rate_steps`` run's (:meth:`run_rate`; every schedule starts from it). 0: the
    same ``learning_rate`` for any run (before issue #54). The evidence
    (:data:`LEARNER_EVIDENCE`): the best step size falls with the run's length. Self-touch at
    2,048,000 steps scored 0.668 [0.622, 0.715] with half the step size against 0.588 with 3e-4
    (5 seeds, every seed up), while the default run (1,024,000 steps) lost with half (0.542
    against 0.622, every seed down) and ``hand_to_mouth`` at 496,640 steps lost most (0.300
    against 0.844); runs of up to 1,024,000 steps (the default run, both plugins, hand regard's
    614,400) train as before. A saved config without this field means 0."""
    normalize_rewards: bool = True
    """Divide every reward by a running standard deviation of the discounted return (as
    gymnasium's ``NormalizeReward`` and SB3's ``VecNormalize``), then clip it to
    +-``reward_clip``, before PPO sees it (:mod:`devlearn.training.reward_norm`). Raw per-term
    rewards are still what metrics.jsonl logs. Unnormalised returns (value loss 5 to 440)
    swamped the policy gradient of every shared-trunk run (issue #28,
    ``results/learner/README.md``). A saved config without this field means False."""
    reward_clip: float = 10.0
    """Bound on a normalised reward (with ``normalize_rewards``)."""
    adam_eps: float = 1e-5
    """Adam's epsilon (SB3's and cleanrl's 1e-5, :data:`LEARNER_EVIDENCE`; torch's default
    1e-8 before issue #54)."""
    normalize_advantage_per_mini_batch: bool = True
    """Standardise advantages in each mini-batch (SB3, :data:`LEARNER_EVIDENCE`) instead of
    once over the rollout (before issue #54)."""

    def run_rate(self, total: int) -> float:
        """The step size of a run of ``total`` steps (``full_rate_steps``'s rule): the fixed
        schedule's, the adaptive one's start and the linear one's before it falls."""
        if not self.full_rate_steps or total <= self.full_rate_steps:
            return self.learning_rate
        return self.learning_rate * max(MIN_RATE_SHARE, self.full_rate_steps / total)

    def linear_rate(self, done: int, total: int) -> float:
        """``schedule=linear``'s step size after ``done`` of ``total`` steps: the run's step
        size (:meth:`run_rate`) until the last ``decay_share`` of the run, then falling linearly
        to 0 at its end."""
        left = max(0.0, 1.0 - done / total)
        return self.run_rate(total) * min(1.0, left / self.decay_share)


MIN_RATE_SHARE = 0.5
"""The smallest share of ``ppo.learning_rate`` that a long run takes (``ppo.full_rate_steps``):
half, the step size measured at twice the full-rate budget (self-touch at 2,048,000 steps);
longer runs keep it, since no longer budget was measured."""


@dataclass
class NetworkConfig:
    """How the networks are laid out; recorded so that older checkpoints rebuild as trained."""

    layout: str = "separate"
    """``separate`` (the default, :data:`LEARNER_EVIDENCE`: issue #28's pilots and the audit of
    the published shared-trunk runs favoured it): actor and critic each have their own
    encoders, fusion and trunk; ``shared``: one set feeds separate policy and value heads (the
    paper); empty: the behaviour's ``NetworkSpec.share``. A saved config without a ``network``
    section (runs from before the shared layout) means ``separate``."""
    legacy_uint8_scale: bool = False
    """Divide uint8 observations (eye images) by 255 twice, as every run before the input-scale
    fix did (the eye CNN divided its already-scaled input again). A saved config without a
    ``network`` section means True, so those checkpoints see the input they were trained on;
    new runs use [0, 1] images."""
    head: str = "free"
    """The policy's action distribution; ``free`` by default (:data:`LEARNER_EVIDENCE`: with
    ``final_std`` its mean action is its behaviour; ``gaussian`` before issue #54).

    ``free``: a linear mean and one free state-independent log-spread per action (SB3's and
    cleanrl's). ``squashed``: that Gaussian squashed by ``tanh``. ``gaussian``: a linear mean
    and one state-independent spread per action, bounded to [``min_std``, the behaviour's
    ``max_std`` (1.0 where it sets none)] by a sigmoid; actions are clipped by the env, and a
    mean past a bound stops being pushed once no sample falls inside (it cannot saturate).
    ``paper``: the paper's ``tanh`` mean with a state-dependent softplus spread (sec. II-A4),
    whose pre-activation grows without limit when the best action lies at a bound, since the
    env clips the samples, not the mean (issue #28). A saved config without this field means
    ``paper``."""
    min_std: float = 0.05
    """Lower bound of the ``gaussian`` head's spread (exploration never vanishes)."""
    init_std: float = 0.0
    """Spread at initialisation; 0: the head's own, 1.0 for ``free`` and ``squashed`` (SB3's,
    :data:`LEARNER_EVIDENCE`), the behaviour's ``NetworkSpec.init_std`` for ``gaussian`` and
    ``paper`` (0.5 unless it says)."""
    final_std: float = 0.3
    """A ceiling on the spread that falls log-linearly from the initial spread to this value
    over the run (every head; :func:`devlearn.training.distribution.spread_cap`): exploration
    wide at first, and at the end a policy whose mean action is its behaviour (issue #54; 0.3
    by default, :data:`LEARNER_EVIDENCE`: 0.1 before, which ended exploration too early). 0: no
    ceiling. A saved config without this field means 0."""
    exploration_beta: float = 1.0
    """The spectrum of the policy's exploration noise over decisions: power ~ f^-beta (every
    head; :class:`devlearn.training.distribution.ColoredNoise`). 1 (the default,
    :data:`LEARNER_EVIDENCE`): pink (Eberhard et al. 2023), a drift that a slightly perturbed
    deterministic policy would make, so training meets the closed loop the mean action plays
    (issue #54); 0: white, independent draws at every decision (SB3's and rsl-rl's; before
    issue #54). Each draw is still the policy's Gaussian: PPO's probabilities are unchanged.
    From 0 to below 2. A saved config without this field means 0."""
    encoders: str = "flat"
    """How senses are encoded; ``flat`` by default (:data:`LEARNER_EVIDENCE`; ``behavior``
    before issue #54). ``behavior``: each observation through the encoder the behaviour's
    ``NetworkSpec`` gives it; ``flat``: every vector observation (an ``MLPEncoder``'s) flattened
    and concatenated straight into the fusion and trunk layers, images keeping their encoders
    (SB3's ``MultiInputPolicy``: one MLP over the vector senses)."""
    activation: str = "tanh"
    """Activation of the encoders' MLPs, fusion and trunk (``tanh`` by default, SB3's,
    :data:`LEARNER_EVIDENCE`; ``relu`` before issue #54; ``elu``...)."""
    init: str = "orthogonal"
    """Weight initialisation; ``orthogonal`` by default (:data:`LEARNER_EVIDENCE`). ``torch``:
    PyTorch's default, then the head's small last layer; ``orthogonal``: SB3's and cleanrl's,
    gain sqrt(2) in hidden layers, 1 on the value output, 0.01 on the policy's mean."""
    normalize: str = "behavior"
    """Observations standardised by running statistics: ``behavior`` (those the behaviour's
    ``NetworkSpec.normalize`` names) or ``all``."""


LEGACY_NETWORK = NetworkConfig(layout="separate", legacy_uint8_scale=True, head="paper")
"""What a saved config without a ``network`` section was trained with."""

HEADS = ("gaussian", "paper", "free", "squashed")
"""Valid values of :attr:`NetworkConfig.head`: the bounded Gaussian, the paper's, the free
Gaussian (SB3's) and the tanh-squashed Gaussian (:mod:`devlearn.training.distribution`)."""
FREE_INIT_STD = 1.0
"""The free and squashed heads' initial spread where ``network.init_std`` is 0 (SB3's
``log_std_init = 0``)."""
ENCODERS = ("behavior", "flat")
"""Valid values of :attr:`NetworkConfig.encoders`."""
INITS = ("torch", "orthogonal")
"""Valid values of :attr:`NetworkConfig.init`."""
NORMALIZE = ("behavior", "all")
"""Valid values of :attr:`NetworkConfig.normalize`."""
LR_SCHEDULES = ("fixed", "adaptive", "linear")
"""Valid values of :attr:`PPOConfig.schedule`."""
ACTIVATIONS = (
    "elu", "selu", "relu", "crelu", "lrelu", "tanh", "sigmoid", "softplus", "gelu", "swish",
    "mish", "identity",
)  # fmt: skip
"""Valid values of :attr:`NetworkConfig.activation`: rsl-rl 5.5.1's activation names
(``rsl_rl.utils.resolve_nn_activation``; listed here so that checking a config loads no torch)."""

LEGACY_FIELDS: dict[str, Any] = {
    "ppo.normalize_rewards": False,
    "network.head": "paper",
    "env.action_repeat": 1,
    "ppo.schedule": "adaptive",
    # issue #54's learner fields: every run saved before them was trained with these
    "ppo.adam_eps": 1e-8,
    "ppo.normalize_advantage_per_mini_batch": False,
    "network.final_std": 0.0,
    "network.encoders": "behavior",
    "network.activation": "relu",
    "network.init": "torch",
    "network.normalize": "behavior",
    "network.exploration_beta": 0.0,
    "ppo.full_rate_steps": 0,
}
"""Core fields a saved run's config may lack, and the value its run was trained with (the
default changed when the field was added, issue #28): such a config loads as trained. A new
run's config file (``devlearn run --config``) takes today's defaults instead."""

LEARNER_EVIDENCE = "results/learners/README.md"
"""Where the core's learner defaults come from: issue #28's pilots and audit
(``results/learner/README.md``: a decision every 5 physics steps, ``env.action_repeat=5``; a
discount of 0.99 per decision and rollouts of 64 decisions; a fixed learning rate; separate
actor and critic; rewards normalised by the running spread of the return) and issue #54's
pilots (``results/learners/README.md``: one flat tanh MLP per network over the vector senses,
orthogonal initialisation, Adam's epsilon 1e-5 and advantages standardised per mini-batch, as
SB3's PPO; a free state-independent spread starting at 1.0 under a ceiling that falls to 0.3
over the run, so that the mean action is the behaviour: 0.3 against 0.1 scored higher with the
mean action on self-touch at 2M and at the default run's 1M, on ``hand_to_mouth`` and on the
behaviour ``devlearn new`` writes; and pink exploration noise, f^-1 over decisions, with which
the mean action of both plugins scored above their sampled actions, and self-touch learned
faster and ended where white exploration and SB3's PPO end; a step size that falls with the
run's length past 1,024,000 steps, ``ppo.full_rate_steps``: half of it scored higher on
self-touch at 2M in every seed and lower at the default run's 1M and the plugins' 0.5M,
``results/learners/README.md``). Every behaviour gets them; a behaviour overrides in
``train_defaults`` only what its own evidence supports (issue #38: a third-party behaviour
learned with these and not with the old defaults; hand regard keeps issue #28's learner, on
which its results stand, white exploration and one step size for any run included)."""


@dataclass
class EnvConfig:
    """How the policy meets the environment."""

    action_repeat: int = 5
    """Physics steps per policy decision: one action is held for this many physics steps and
    their rewards summed (``env.action_repeat=K``; how facts and rewards are computed within
    a decision: ``Behavior.facts_every_physics_step``). Episode lengths, curriculum stages,
    ``--steps`` and evaluation counts stay in physics steps. The default 5 is a decision every
    25 ms: at 200 Hz (1, the paper's rate, its ``--preset paper``) independent noise held for
    5 ms barely moves an arm, so random exploration goes nowhere (issue #28,
    :data:`LEARNER_EVIDENCE`). A saved run's config without this field means 1. Must divide
    the episode length."""
    action_noise_std: float = 0.0
    """Motor noise: the standard deviation, per actuator and in action units (a fraction of
    each motor's maximum torque), of time-correlated Gaussian noise added to every action the
    env applies, at every physics step, before the clip to [-1, 1]; in training and in every
    evaluation of the run's policy (it is the body's). 0 (default): none. Seeded per env,
    independent of the initial poses, never reset (it runs on through episodes and sessions),
    saved in checkpoints (:mod:`devlearn.env.motor_noise`). From 0 to 1."""
    action_noise_beta: float = 0.88
    """The motor noise's spectrum: its power falls as f^-beta from 0.01 Hz to the Nyquist
    frequency. Infants' hand-velocity spectra: beta 0.69 at 8 weeks to 0.88 at 30 weeks
    (Ernst, Lopez, Hoffmann and Triesch, arXiv 2606.16590); the default is the older infants'
    (our body is 18 months old by default). 0: white noise. From 0 to below 2."""


@dataclass
class InfantConfig:
    """The infant's body: its age, fixed or growing over the run (issue #41)."""

    age_months: float | None = None
    """Build the body at this age, 0 to 24 months: its crown-heel length and weight the WHO
    boys' medians, its proportions (the head's share of its length falls with age), masses,
    inertias, motor torques and skin from growth curves (``devlearn/infant/growth.py``; the
    same 68 skin regions with the same sensors, spread over the larger body, so observations
    keep their shape). Unset (null, the default): the default body, MIMo v1's 18-month-old
    (77.8 cm, 10.96 kg: the WHO median length at 13.8 months, weight at 18.1), exactly as every
    published run was trained. ``devlearn eval --set infant.age_months=A`` evaluates a policy
    at age A."""
    growth: str = ""
    """Grow while learning: ``A->B`` (A months at the start, B at the end, the run cut into
    pieces of ``growth_every`` steps at ages evenly between, e.g. ``6->18``), ``A,B,...``
    (the run in equal parts at these ages, e.g. ``6,12,18``) or ``stages:A,B,...`` (one age
    per curriculum stage, e.g. ``stages:6,18``: self_touch's fixed-pose and random-pose
    stages); empty: no growth. Quote it in a shell (``--set 'infant.growth=6->18'``). At an
    iteration boundary where the age changes, every env rebuilds its physics at the new age
    and carries on with the same joint angles and velocities; the policy, optimiser and
    reward memories carry over, checkpoints record the age and a resumed run continues at its
    schedule's age. A resume keeps the schedule (another ``infant.growth`` is refused; with
    another ``--steps`` the schedule keeps the steps it spans, ``growth_steps``, so the age
    never goes back). Excludes ``age_months``."""
    growth_every: int = 0
    """Steps per piece of an ``A->B`` growth schedule (0: 24 pieces over the run)."""
    growth_steps: int = 0
    """Steps the growth schedule spans (0: the run's ``total_steps``); past them the body keeps
    the last age. A run resumed with another ``--steps`` records its old ``total_steps`` here,
    so that its body's age at every step stays what the schedule gave it."""


@dataclass
class RunConfig:
    """Everything one ``devlearn run`` needs; saved as ``config.json`` in the run directory."""

    behavior_name: str = ""
    """Registered behaviour to train (``devlearn plugins`` lists them)."""
    total_steps: int = 150_000
    """Environment steps to train for, summed over all environments and ranks. The default is a
    demonstration (a few minutes on a 2-core CPU, docs/scaling.md); the paper's runs are
    millions (``--steps 8e6``)."""
    num_envs: int = 16
    """Environments per rank. 16 amortises the policy's per-step forward pass (about 2 ms on
    one core whatever the batch up to ~16) and gives 2,048-sample rollouts at 128 steps."""
    workers: int = -1
    """Environment worker processes per rank (0: step environments in the training process;
    -1: automatic, one per CPU core but at most ``num_envs // 4``, so small batches stay in
    process where a worker's start-up and per-step round trip would cost more than it gains)."""
    seed: int = 0
    """Seed of torch, numpy, random and (plus the env index) every environment."""
    device: str = "cpu"
    """Torch device of the networks (``cpu`` or ``cuda``; ``cuda:LOCAL_RANK`` when distributed)."""
    out_dir: str = ""
    """Run directory (config, checkpoints, metrics.jsonl, TensorBoard); default runs/NAME-TIME."""
    save_interval: int = 50
    """Iterations between periodic ``checkpoint_<step>.pt`` files; ``checkpoint_latest.pt`` is
    also written every ``save_interval // 10`` iterations (at least every iteration)."""
    torch_threads: int = 0
    """Torch threads of the training process while collecting and updating (0: automatic, all
    cores this process may use while the env workers wait, falling back to one thread while
    another program makes multi-threaded work slower; see ``ThreadPlan`` in
    ``devlearn/training/process.py``). Results repeat bit for bit only for a fixed count."""
    update_threads: int = 0
    """Threads of the PPO update (0: the same as ``torch_threads``)."""
    logger: str = "tensorboard"
    """Where metrics go besides metrics.jsonl: ``tensorboard``, or ``wandb`` (Weights & Biases
    through rsl-rl's writer, which also writes TensorBoard; needs ``devlearn[wandb]``;
    ``WANDB_MODE=offline`` keeps it local)."""
    wandb_project: str = "devlearn"
    """W&B project of the run (with ``logger=wandb``); the run is named after its directory."""
    ppo: PPOConfig = field(default_factory=PPOConfig)
    """PPO hyper-parameters."""
    network: NetworkConfig = field(default_factory=NetworkConfig)
    """Network layout, policy head and input scale."""
    env: EnvConfig = field(default_factory=EnvConfig)
    """The decision rate."""
    infant: InfantConfig = field(default_factory=InfantConfig)
    """The infant's age, fixed or growing."""
    curiosity: list[str] = field(default_factory=list)
    """Learned intrinsic rewards added to the behaviour's reward, by registered name
    (``--set curiosity=rnd,forward_model``; ``devlearn plugins --json`` lists them). Each is a
    model trained on every rollout (devlearn/api/learned.py); none by default."""
    learned: dict[str, Any] = field(default_factory=dict)
    """Options of the learned rewards, name -> {option: value}, e.g. ``--set
    learned.rnd.weight=0.5`` (the fields of the term's ``config_class``; unset ones keep their
    defaults, and config.json records every resolved value)."""
    preset: str = ""
    """The behaviour preset this run started from (``devlearn run --preset NAME``; recorded
    only: config.json holds every resolved value). Empty: none."""
    start_from: str = ""
    """The checkpoint this run started from (``devlearn run --from CHECKPOINT``; recorded
    only). Empty: a fresh start."""
    behavior: Any = None
    """The behaviour's own options (an instance of its ``config_class``)."""


def new_config(behavior_cls: type[Behavior]) -> RunConfig:
    """The core defaults with the behaviour's config class's defaults: the base every run
    config starts from (:func:`devlearn.config.resolve.resolve_run`, :func:`from_dict`)."""
    return RunConfig(behavior_name=behavior_cls.name, behavior=behavior_cls.config_class())


def finish_config(cfg: RunConfig, behavior: Behavior) -> None:
    """Check ``cfg`` against the network ``behavior`` (the behaviour built on it) builds
    under it and record the layout the behaviour chooses where ``network.layout`` is empty (so
    config.json says it).

    Raises:
        UsageError: The behaviour's ``network()`` rejects the config, or the head, spread
            bounds or decision rate are invalid (:func:`check_learner`).
    """
    name = type(behavior).name
    try:  # the spec checks its own values (e.g. the spread): say so before any env starts
        spec = behavior.network()
    except ValueError as err:
        raise UsageError(
            f"{name}: its network() rejects the config: {err} "
            "(set through --set behavior.FIELD=VALUE, e.g. behavior.max_std)"
        ) from err
    try:  # stage lengths are the behaviour's fields: a negative one fails here, not in a worker
        behavior.curriculum()
    except ValueError as err:
        raise UsageError(f"{name}: its curriculum() rejects the config: {err}") from err
    if not cfg.network.layout:
        cfg.network.layout = "shared" if spec.share else "separate"
    if cfg.network.layout == "shared":  # one body serves one set of observations
        groups = spec.obs_groups(list(spec.encoders))
        if set(groups["actor"]) != set(groups["critic"]):
            raise UsageError(
                f"{name}: network.layout=shared needs the actor and the critic to see the same "
                f"observations; this config's actor sees {groups['actor']}, its critic "
                f"{groups['critic']}: use network.layout=separate"
            )
    check_learner(cfg, spec)


def check_learner(cfg: RunConfig, spec: Any) -> None:
    """Check the head, spread bounds and decision rate of a run config.

    Raises:
        UsageError: naming the ``--set`` key and what is valid.
    """
    net = cfg.network
    for key, value, valid in (
        ("head", net.head, HEADS),
        ("encoders", net.encoders, ENCODERS),
        ("init", net.init, INITS),
        ("normalize", net.normalize, NORMALIZE),
        ("activation", net.activation, ACTIVATIONS),
    ):
        if value not in valid:
            raise UsageError(f"unknown network.{key} '{value}'; valid: {', '.join(valid)}")
    if net.init_std < 0:
        raise UsageError(
            f"network.init_std must be 0 (the head's own) or above, got {net.init_std}"
        )
    init_std = initial_std(cfg, spec)
    if net.head == "gaussian" and not 0 < net.min_std < min(init_std, head_max_std(spec)):
        raise UsageError(
            f"network.min_std must be above 0 and below the initial spread {init_std} "
            f"and the bound {head_max_std(spec)}; got {net.min_std}"
        )
    if net.head == "gaussian" and not init_std < head_max_std(spec):
        raise UsageError(
            f"network.init_std must be below the spread's bound {head_max_std(spec)}, "
            f"got {init_std}"
        )
    floor = net.min_std if net.head == "gaussian" else 0.0
    if net.final_std and not floor <= net.final_std < init_std:
        raise UsageError(
            f"network.final_std must lie in [{floor}, {init_std}) (the spread's lower bound "
            f"and its initial value), got {net.final_std}"
        )
    if cfg.ppo.adam_eps <= 0:
        raise UsageError(f"ppo.adam_eps must be above 0, got {cfg.ppo.adam_eps}")
    if cfg.env.action_repeat < 1:
        raise UsageError(f"env.action_repeat must be at least 1, got {cfg.env.action_repeat}")
    if cfg.ppo.normalize_rewards and not cfg.ppo.reward_clip > 0:
        raise UsageError(f"ppo.reward_clip must be above 0, got {cfg.ppo.reward_clip}")


def initial_std(cfg: RunConfig, spec: Any) -> float:
    """The policy's spread at initialisation: ``network.init_std``, else the head's own (1.0
    for the free and squashed heads, SB3's; the behaviour's for the others)."""
    if cfg.network.init_std:
        return float(cfg.network.init_std)
    return FREE_INIT_STD if cfg.network.head in ("free", "squashed") else float(spec.init_std)


def head_max_std(spec: Any) -> float:
    """Upper bound of the ``gaussian`` head's spread: the behaviour's ``max_std``, or 1.0 (the
    widest useful spread for actions clipped to [-1, 1]) where it sets none."""
    return float(spec.max_std) if spec.max_std else 1.0


def to_dict(cfg: RunConfig) -> dict[str, Any]:
    """Return a JSON-ready dict of ``cfg`` (tuples become lists)."""
    return json.loads(json.dumps(dataclasses.asdict(cfg)))


def _fill(obj: Any, data: dict[str, Any], prefix: str) -> None:
    hints = field_types(obj)
    for name, value in data.items():
        current = getattr(obj, name, None)
        if dataclasses.is_dataclass(current):
            if not isinstance(value, dict):
                shown = repr(value) if len(repr(value)) <= 40 else repr(value)[:37] + "..."
                raise UsageError(
                    f"saved config is damaged: '{prefix}{name}' holds {shown}, "
                    "not a table of its fields"
                )
            _fill(current, value, f"{prefix}{name}.")
        elif name in {f.name for f in dataclasses.fields(obj)}:
            setattr(obj, name, convert(value, hints.get(name, Any), prefix + name))
        else:
            raise UsageError(f"unknown config key '{prefix}{name}' in saved config")


def from_dict(
    data: dict[str, Any], behavior_cls: type[Behavior], base: RunConfig | None = None
) -> RunConfig:
    """Rebuild a RunConfig saved by :func:`to_dict` for the behaviour class ``behavior_cls``.

    A saved run's config (a checkpoint's, a run folder's; no ``base``): a key it lacks takes
    its default, except where the old runs were trained otherwise: a missing ``network``
    section means :data:`LEGACY_NETWORK`, a core field of :data:`LEGACY_FIELDS` takes its
    value there, and a behaviour field named in its config class's
    :attr:`~devlearn.api.behavior.BehaviorConfig.LEGACY_DEFAULTS` (field -> value) that the
    saved ``behavior`` section lacks takes that value (a default changed after those runs).

    ``base``: ``data`` is a new run's config file (``devlearn run --config``), filled into
    ``base`` (in place), a fresh run's config: a key it lacks keeps today's defaults, the
    behaviour's ``train_defaults()`` included (:func:`devlearn.config.resolve.resolve_run`
    builds it), never the values old runs were trained with.
    """
    new_run = base is not None
    cfg = base if base is not None else new_config(behavior_cls)
    if not new_run and "network" not in data:
        cfg.network = dataclasses.replace(LEGACY_NETWORK)
    for key, value in {} if new_run else LEGACY_FIELDS.items():
        section, name = key.split(".")
        if name not in (data.get(section) or {}):
            setattr(getattr(cfg, section), name, value)
    saved = data.get("behavior")
    if isinstance(saved, dict) and cfg.behavior is not None:
        # reward fields a config saved before issue #31 holds move into ``rewards``
        declared = isinstance(cfg.behavior, BehaviorConfig)
        moves = cfg.behavior.LEGACY_REWARD_KEYS if declared else {}
        saved = upgrade_saved_rewards(saved, moves, type(cfg.behavior))
        data = {**data, "behavior": saved}
        legacy = cfg.behavior.LEGACY_DEFAULTS if declared and not new_run else {}
        _fill(cfg.behavior, {k: v for k, v in legacy.items() if k not in saved}, "behavior.")
    _fill(cfg, data, "")
    check_reward_table(cfg.behavior)
    return cfg


def shared_layout(cfg: RunConfig, spec: Any) -> bool:
    """Whether this run shares encoders, fusion and trunk between policy and value.

    Raises:
        UsageError: ``network.layout`` is neither ``shared``, ``separate`` nor empty.
    """
    layouts = {"shared": True, "separate": False, "": bool(spec.share)}
    if cfg.network.layout not in layouts:
        raise UsageError(
            f"unknown network.layout '{cfg.network.layout}'; valid: shared, separate "
            "(or empty: the behaviour's NetworkSpec.share)"
        )
    return layouts[cfg.network.layout]


def learner_spec(spec: Any, net: NetworkConfig) -> Any:
    """The behaviour's NetworkSpec as the run's ``network`` section shapes it: flat encoders
    (every observation flattened into the fusion layers), the encoders' activation, every
    observation normalised. The defaults return ``spec`` itself."""
    from devlearn.api.sensors import FlattenEncoder, MLPEncoder

    encoders: dict[str, Any]
    if net.encoders == "flat":  # vector senses only: an image keeps its CNN (as SB3's extractor)
        encoders = {
            name: FlattenEncoder() if isinstance(enc, MLPEncoder) else enc
            for name, enc in spec.encoders.items()
        }
    else:
        encoders = {
            name: MLPEncoder(enc.hidden_dims, net.activation)
            if isinstance(enc, MLPEncoder) and net.activation != enc.activation
            else enc
            for name, enc in spec.encoders.items()
        }
    normalize = tuple(spec.encoders) if net.normalize == "all" else tuple(spec.normalize)
    if encoders == spec.encoders and normalize == tuple(spec.normalize):
        return spec
    return dataclasses.replace(spec, encoders=encoders, normalize=normalize)


def to_rsl_rl(cfg: RunConfig, behavior: Any, observation_names: list[str] | None = None) -> dict:
    """Return rsl-rl 5.5.1's ``train_cfg`` for this run.

    Actor and critic are :class:`~devlearn.training.networks.MultiSenseModel`s built from the
    behaviour's :class:`~devlearn.api.network_spec.NetworkSpec` (passed as an object; rsl-rl
    deep-copies it). In the ``shared`` layout rsl-rl's ``share_cnn_encoders`` hands the actor's
    encoders, fusion and trunk to the critic, which adds only its value head; in the ``separate``
    layout each network builds its own. The algorithm is
    :class:`~devlearn.training.ppo.UniqueParamPPO`.

    Args:
        cfg: The run config.
        behavior: The behaviour instance.
        observation_names: Observation names (default: the spec's encoder names).
    """
    spec = learner_spec(behavior.network(), cfg.network)
    names = list(observation_names or spec.encoders)
    ppo = dataclasses.asdict(cfg.ppo)
    num_steps = ppo.pop("num_steps_per_env")
    for ours in ("normalize_rewards", "reward_clip", "decay_share", "full_rate_steps"):
        ppo.pop(ours)  # devlearn's, not rsl-rl's
    ppo["learning_rate"] = cfg.ppo.run_rate(cfg.total_steps)
    shared = shared_layout(cfg, spec)
    model = {
        "class_name": "devlearn.training.networks:MultiSenseModel",
        "spec": spec,
        "shared": shared,
        "legacy_uint8_scale": cfg.network.legacy_uint8_scale,
        "activation": cfg.network.activation,
        "init": cfg.network.init,
    }
    init_std = initial_std(cfg, spec)
    head = cfg.network.head
    if head == "paper":
        distribution = {
            "class_name": "devlearn.training.networks:TanhSoftplusGaussian",
            "init_std": init_std,
            "max_std": spec.max_std,
        }
    elif head in ("free", "squashed"):
        distribution = {
            "class_name": "devlearn.training.distribution:"
            + ("FreeGaussian" if head == "free" else "SquashedGaussian"),
            "init_std": init_std,
        }
    else:
        distribution = {
            "class_name": "devlearn.training.distribution:BoundedGaussian",
            "init_std": init_std,
            "min_std": cfg.network.min_std,
            "max_std": head_max_std(spec),
        }
    if cfg.network.final_std:  # absent otherwise: configs from before issue #54 build as then
        distribution["final_std"] = cfg.network.final_std
    if cfg.network.exploration_beta:  # absent otherwise: white noise, as every run before
        distribution["noise_beta"] = cfg.network.exploration_beta
        distribution["noise_decision_s"] = PHYSICS_TIMESTEP * cfg.env.action_repeat
    return {
        "algorithm": {
            "class_name": "devlearn.training.ppo:UniqueParamPPO",
            "share_cnn_encoders": shared,
            **ppo,
        },
        "actor": {**model, "distribution_cfg": distribution},
        "critic": dict(model),
        "obs_groups": spec.obs_groups(names),
        "num_steps_per_env": num_steps,
        "save_interval": cfg.save_interval,
        "run_name": cfg.behavior_name,
        "logger": "tensorboard",
        "check_for_nan": True,
    }
