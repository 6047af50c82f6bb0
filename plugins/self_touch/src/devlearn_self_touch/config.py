"""Options of the self_touch behaviour: every constant of the paper's Model I (sec. II-A)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

from devlearn.api.behavior import BehaviorConfig
from devlearn.api.rewards import RewardTermCfg, reward_term_cfg
from devlearn_self_touch.activity import ActivityLevel, ContactTime, Effort, TouchOnset
from devlearn_self_touch.rewards import (
    LIFETIME_MEMORIES,
    TOUCH_COUNTS,
    Balance,
    ContactNovelty,
    DiversityMilestones,
    TouchNovelty,
)

CURRICULA = ("two_stage", "fixed_only", "random_only")
"""Valid values of :attr:`SelfTouchConfig.curriculum` (paper sec. II-A5 and its ablation)."""

TOUCH_SOURCES = ("hands", "hands_or_threshold", "threshold")
"""Valid values of :attr:`SelfTouchConfig.touch_source`."""


def paper_rewards() -> dict[str, RewardTermCfg]:
    """R_t = R_touch + R_geom + R_milestones + R_balance (sec. II-A3): the paper's four terms,
    weight 1 each, with its constants."""
    return {
        "touch_novelty": RewardTermCfg(
            TouchNovelty,
            1.0,
            {
                "first_ever": 5.0,
                "first_in_episode": 1.0,
                "repeat_scale": 0.5,
                "midpoint": 10.0,
                "rate": 0.5,
            },
        ),
        "contact_novelty": RewardTermCfg(
            ContactNovelty, 1.0, {"first_ever": 10.0, "first_in_episode": 2.0}
        ),
        "diversity_milestones": RewardTermCfg(
            DiversityMilestones, 1.0, {"reward": 5.0, "milestones": (5, 10, 15, 20, 25, 30)}
        ),
        "balance": RewardTermCfg(Balance, 1.0, {"reward": 10.0, "tolerance": 3, "min_parts": 0}),
    }


NOT_IN_PAPER = ("activity_level", "effort", "contact_time", "touch_onset")
"""Our reward terms beside the paper's (issue #57's infant-like variants,
:mod:`devlearn_self_touch.activity`): in the default table at weight 0, and left out of a run
while their weight is 0, so that a run without them is the paper's reward exactly."""


def default_rewards() -> dict[str, RewardTermCfg]:
    """The default table: the paper's four terms (:func:`paper_rewards`), then ours
    (:data:`NOT_IN_PAPER`) at weight 0: off, but declared, so ``--set
    behavior.rewards.effort.weight=0.5`` switches one on."""
    return {
        **paper_rewards(),
        "activity_level": RewardTermCfg(
            ActivityLevel,
            0.0,
            {"preferred": 0.1, "time_constant_s": 1.0, "signal": "hand_speed"},
        ),
        "effort": RewardTermCfg(Effort, 0.0, {}),
        "contact_time": RewardTermCfg(ContactTime, 0.0, {"free_s": 0.5}),
        "touch_onset": RewardTermCfg(TouchOnset, 0.0, {"min_gap_s": 2 / 30, "surface": False}),
    }


@dataclass
class SelfTouchConfig(BehaviorConfig):
    """Options of :class:`devlearn_self_touch.SelfTouch`; overridable as ``--set behavior.X=V``.

    Defaults reproduce the paper (Baby Sophia, sec. II-A) unless a field says otherwise: the
    policy spread is bounded (``max_std`` 1.0) and the lifetime memory is the run's
    (``lifetime_memory`` shared), the recipe ``results/self_touch/README.md`` supports. The
    paper's values are ``devlearn run self_touch --preset paper``
    (:data:`devlearn_self_touch.behavior.PRESETS`).
    """

    LEGACY_DEFAULTS: ClassVar[dict[str, Any]] = {
        "max_std": 0.0,
        "lifetime_memory": "per_env",
        "touch_count": "step",
        # issue #57: runs saved before the reward's clock counted the rewards table's steps
        # and played the infant's 5 s episodes
        "repeat_crossing_s": None,
        "repeat_steepness_s": None,
        "episode_s": None,
    }
    """Values a saved config (config.json, a checkpoint's config) that lacks the field was
    trained with: runs from before these fields existed, or before their defaults changed
    (issue #20), load and resume as trained (read by ``devlearn.config.run_config.from_dict``)."""

    LEGACY_REWARD_KEYS: ClassVar[dict[str, str]] = {
        "weight_touch_novelty": "touch_novelty.weight",
        "touch_first_ever": "touch_novelty.params.first_ever",
        "touch_first_in_episode": "touch_novelty.params.first_in_episode",
        "touch_repeat_scale": "touch_novelty.params.repeat_scale",
        "decay_midpoint": "touch_novelty.params.midpoint",
        "decay_rate": "touch_novelty.params.rate",
        "weight_contact_novelty": "contact_novelty.weight",
        "contact_first_ever": "contact_novelty.params.first_ever",
        "contact_first_in_episode": "contact_novelty.params.first_in_episode",
        "weight_diversity_milestones": "diversity_milestones.weight",
        "milestone_reward": "diversity_milestones.params.reward",
        "milestones": "diversity_milestones.params.milestones",
        "weight_balance": "balance.weight",
        "balance_reward": "balance.params.reward",
        "balance_tolerance": "balance.params.tolerance",
        "balance_min_parts": "balance.params.min_parts",
    }
    """Fields of configs saved before issue #31 that now live in :attr:`rewards` (old field ->
    ``TERM.weight`` or ``TERM.params.NAME``); such a config loads with them moved there
    (:func:`devlearn.api.rewards.upgrade_saved_rewards`)."""

    # --- what counts as "touched" (sec. II-A2/A3) ----------------------------------------
    touch_source: str = "hands"
    """How a region is marked touched for the touch-novelty and milestone terms.
    ``"hands"`` (default): a palm or finger touches it (``Infant.hand_contacts``; the mattress
    can never produce one). ``"threshold"``: the paper's literal rule g_j > ``touch_threshold``
    (sec. II-A3), which on our skin also counts lying on the mattress. ``"hands_or_threshold"``:
    either. We measured mattress-only and self-touch g_j to overlap entirely (README,
    ``python -m devlearn_self_touch.calibrate``), so no threshold separates them."""
    touch_threshold: float = 0.1
    """Threshold on g_j (N per sensor) for the ``threshold`` sources (paper: 0.1, in MIMo's
    units, sec. II-A3). Lying still, mattress regions read 0.12 (median) to 1.0 N."""
    body_map_scale: float = 0.1
    """Observation scaling: the policy sees log1p(g / body_map_scale). With 0.1 N a typical
    hand touch (0.3 N) reads 1.4, the weight on the mattress 0.7 to 2.4, a hard kick (30 N)
    5.7, instead of raw values spanning four orders of magnitude."""

    # --- reward terms (R_t = R_touch + R_geom + R_milestones + R_balance, sec. II-A3) ----
    rewards: dict[str, RewardTermCfg] = field(default_factory=default_rewards)
    """Term name -> (class, weight, params) (:func:`default_rewards`: the paper's four terms
    with its constants, :func:`paper_rewards`, and three of ours at weight 0, off):
    ``touch_novelty`` (R_touch: first_ever, first_in_episode, repeat_scale and f_decay's
    midpoint and rate, f_decay(c) = 2 / (1 + exp(rate (c - midpoint))) - 1, in counts of c:
    touches with ``touch_count=onset``; with ``step``, ``repeat_crossing_s`` and
    ``repeat_steepness_s`` set them in seconds unless null), ``contact_novelty``
    (R_geom: first_ever, first_in_episode per (hand, region) pair), ``diversity_milestones``
    (R_milestones: reward per milestone of distinct touched regions crossed in the episode) and
    ``balance`` (R_balance: reward on the last step when |N_L - N_R| <= tolerance and
    N_L + N_R >= min_parts; the paper's min_parts is 0, so an episode without any touch also
    pays). ``--set behavior.rewards.balance.weight=0`` switches one off. Ours (issue #57,
    :mod:`devlearn_self_touch.activity`, costs per simulated second, left out while their
    weight is 0): ``activity_level``, a rest drive, -|m - preferred| per second with m the
    running mean over ``time_constant_s`` seconds of ``signal`` (``hand_speed`` in m/s or
    ``joint_speed`` in rad/s); ``effort``, -mean squared motor command per second;
    ``contact_time``, -1 per second per hand on the body after each bout's first ``free_s``
    seconds; ``touch_onset``, -1 per touch as a video coder counts it (a hand's new bout on the
    body after ``min_gap_s`` seconds off it)."""

    # --- touch novelty R_touch (sec. II-A3) ------------------------------------------------
    lifetime_memory: str = "shared"
    """Whose lifetime the "first ever" bonuses (``touch_novelty`` and ``contact_novelty``)
    count over. ``"shared"`` (default): the run's, as for the paper's one agent; one memory
    for all environments, merged across env workers (and torchrun ranks) at every PPO
    iteration boundary, so between two merges a discovery is paid at most once per worker.
    ``"per_env"``: each environment's own (a discovery can be paid once per environment, 16
    times with 16 envs); every run before issue #20 used it, and a saved config without this
    field means it."""
    touch_count: str = "onset"
    """What ``touch_novelty``'s c_j counts and when repeats pay. ``onset`` (default): touch
    events only (a touch's first step counts and pays; holding it costs nothing more); in the
    300k pilots of issue #28 it raised the training per-episode score from 0.20-0.24 to
    0.30-0.32 (2 seeds each, ``results/learner/README.md``). ``step`` (the paper's literal
    rule, ``--preset paper``): every step a region is touched, so a region held for a whole
    episode costs about -489. A saved config without this field means ``step``."""

    # --- the reward's clock, in simulated seconds (issue #57) ------------------------------
    repeat_crossing_s: float | None = 0.05
    """With ``touch_count=step``: how long (simulated seconds) a region may have been touched
    in an episode before touch novelty's repeat pay turns from reward to penalty, f_decay's
    zero crossing (the paper's c = 10 steps at 200 Hz: 0.05 s). Converted with the body's
    physics step, the reward terms' clock (self-touch's facts and rewards run at every physics
    step whatever ``env.action_repeat``), into the rewards table's ``midpoint``, which it
    replaces: 10 steps at 200 Hz, 20 at 400 Hz. null: the table's ``midpoint``, in steps (what
    a saved config without this field means). Unused with ``touch_count=onset``, where c_j
    counts touches, not time (the table's ``midpoint``: the 10th touch)."""
    repeat_steepness_s: float | None = 0.01
    """With ``touch_count=step``: f_decay's time constant 1 / rate in simulated seconds (the
    paper's rate 0.5 per step at 200 Hz: 0.01 s), converted with the physics step into the
    table's ``rate``, which it replaces. null: the table's ``rate`` (with
    ``repeat_crossing_s`` null; a saved config without this field)."""
    episode_s: float | None = None
    """Simulated seconds per episode, in training and evaluation (converted with the physics
    step; a whole number of decisions: 5 s is 1,000 physics steps at 200 Hz, 200 decisions at
    ``env.action_repeat`` 5). null (default): the infant's, BabyBench's 5 s (the paper's).
    The episode is the clock of every per-episode memory: first-in-episode pay, milestones,
    the balance bonus on its last step. ``devlearn eval --session S`` overrides it for an
    evaluation (whole sessions without a reset)."""

    # --- policy (sec. II-A4) -----------------------------------------------------------------
    max_std: float = 1.0
    """Upper bound on the policy's standard deviation (default 1.0, bounded with a sigmoid);
    0: unbounded softplus (the paper, ``--preset paper``). The environment clips actions to
    [-1, 1], and with the paper's spread it grew to ~1,000 over 8M steps, so training actions
    became +-1 noise (``results/self_touch/README.md``). A saved config without this field
    means 0 (runs before issue #20)."""

    # --- curriculum (sec. II-A5) ------------------------------------------------------------
    curriculum: str = "two_stage"
    """``"two_stage"`` (fixed pose then random pose), ``"fixed_only"`` or ``"random_only"``
    (the paper's ablation, Table II)."""
    fixed_pose_steps: int = 4_000_000
    """Environment steps (all environments) of stage 1, fixed initial pose (paper: 4M). A new
    run's default is half its ``total_steps``
    (:func:`~devlearn_self_touch.behavior.stages_as_halves`)."""
    random_pose_steps: int = 4_000_000
    """Environment steps of stage 2, random initial joint angles (paper: 4M; a new run's
    default: the other half). Informational: the last stage lasts until training ends."""

    # --- metrics (BabyBench's scoring) ----------------------------------------------------
    training_score_episodes: int = 10_000
    """Window of the training score logged as ``metrics/training_score``: the last this many
    finished training episodes of the run (all environments, workers and ranks), as
    BabyBench's "training score", the paper's 0.88 (BabyBench: 10,000). Each hand's distinct
    parts (of 34) touched in any episode of the window, (left + right) / 68
    (:class:`devlearn_self_touch.evaluation.TrainingScore`); saved in checkpoints."""

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """Raise ValueError naming a wrong choice and the valid ones."""
        if self.curriculum not in CURRICULA:
            raise ValueError(
                f"unknown curriculum '{self.curriculum}'; valid: {', '.join(CURRICULA)}"
            )
        if self.lifetime_memory not in LIFETIME_MEMORIES:
            raise ValueError(
                f"unknown lifetime_memory '{self.lifetime_memory}'; "
                f"valid: {', '.join(LIFETIME_MEMORIES)}"
            )
        if self.touch_source not in TOUCH_SOURCES:
            raise ValueError(
                f"unknown touch_source '{self.touch_source}'; valid: {', '.join(TOUCH_SOURCES)}"
            )
        if self.touch_count not in TOUCH_COUNTS:
            raise ValueError(
                f"unknown touch_count '{self.touch_count}'; valid: {', '.join(TOUCH_COUNTS)}"
            )
        if self.training_score_episodes < 1:
            raise ValueError(
                f"training_score_episodes must be at least 1, got {self.training_score_episodes}"
            )
        unknown = set(self.rewards) - set(default_rewards())
        if unknown:  # the behaviour passes lifetime_memory and touch_count to its own terms
            raise ValueError(
                f"unknown self_touch reward term(s) {sorted(unknown)}; "
                f"valid: {', '.join(default_rewards())}"
            )
        self._validate_clock()
        for name in NOT_IN_PAPER:  # our terms check their own params' values when built
            if name in self.rewards:
                try:
                    reward_term_cfg(self.rewards[name]).build(name)
                except TypeError:  # an unknown param: check_reward_table names the valid ones
                    pass

    def _validate_clock(self) -> None:
        """The reward's clock: positive seconds, given where the table would not say otherwise."""
        if self.episode_s is not None and not 0 < self.episode_s < float("inf"):
            raise ValueError(f"episode_s must be above 0 seconds (or null), got {self.episode_s}")
        crossing, steepness = self.repeat_crossing_s, self.repeat_steepness_s
        if (crossing is None) != (steepness is None):
            raise ValueError(
                "repeat_crossing_s and repeat_steepness_s are set together (seconds) or both "
                f"null (the rewards table's steps); got {crossing}, {steepness}"
            )
        if crossing is not None and steepness is not None and not min(crossing, steepness) > 0:
            raise ValueError(
                f"repeat_crossing_s and repeat_steepness_s must be above 0, got {crossing}, "
                f"{steepness}"
            )
        term = self.rewards.get("touch_novelty")
        params = {} if term is None else dict(reward_term_cfg(term).params)
        for key in ("lifetime_memory", "touch_count", "crossing_s", "steepness_s"):
            if key in params:
                option = {"crossing_s": "repeat_crossing_s", "steepness_s": "repeat_steepness_s"}
                raise ValueError(
                    f"behavior.rewards.touch_novelty.params.{key} is the behaviour's: set "
                    f"behavior.{option.get(key, key)}"
                )
        paper = paper_rewards()["touch_novelty"].params
        if self.touch_count == "step" and crossing is not None:
            for key, seconds in (("midpoint", "repeat_crossing_s"), ("rate", "repeat_steepness_s")):
                if params.get(key, paper[key]) != paper[key]:
                    raise ValueError(
                        f"with touch_count=step the repeat pay's clock is behavior.{seconds} "
                        f"(seconds); behavior.rewards.touch_novelty.params.{key}="
                        f"{params[key]} counts touches (touch_count=onset). Give it in "
                        f"seconds, or set behavior.repeat_crossing_s=null and "
                        "behavior.repeat_steepness_s=null to count steps"
                    )
