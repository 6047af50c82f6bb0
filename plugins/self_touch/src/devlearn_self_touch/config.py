"""Options of the self_touch behaviour: every constant of the paper's Model I (sec. II-A)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from devlearn_self_touch.batched_rewards import LIFETIME_MEMORIES
from devlearn_self_touch.rewards import TOUCH_COUNTS

CURRICULA = ("two_stage", "fixed_only", "random_only")
"""Valid values of :attr:`SelfTouchConfig.curriculum` (paper sec. II-A5 and its ablation)."""

TOUCH_SOURCES = ("hands", "hands_or_threshold", "threshold")
"""Valid values of :attr:`SelfTouchConfig.touch_source`."""


@dataclass
class SelfTouchConfig:
    """Options of :class:`devlearn_self_touch.SelfTouch`; overridable as ``--set behavior.X=V``.

    Defaults reproduce the paper (Baby Sophia, sec. II-A) unless a field says otherwise: the
    policy spread is bounded (``max_std`` 1.0) and the lifetime memory is the run's
    (``lifetime_memory`` shared), the recipe ``results/self_touch/README.md`` supports. The
    paper's values are ``devlearn run self_touch --preset paper``
    (:meth:`devlearn_self_touch.SelfTouch.presets`).
    """

    LEGACY_DEFAULTS: ClassVar[dict[str, Any]] = {
        "max_std": 0.0,
        "lifetime_memory": "per_env",
        "touch_count": "step",
    }
    """Values a saved config (config.json, a checkpoint's config) that lacks the field was
    trained with: runs from before these fields existed, or before their defaults changed
    (issue #20), load and resume as trained (read by ``devlearn.config.run_config.from_dict``)."""

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

    # --- reward weights (R_t = R_touch + R_geom + R_milestones + R_balance, sec. II-A3) -----
    weight_touch_novelty: float = 1.0
    """Weight of R_touch (paper: 1)."""
    weight_contact_novelty: float = 1.0
    """Weight of R_geom (paper: 1)."""
    weight_diversity_milestones: float = 1.0
    """Weight of R_milestones (paper: 1)."""
    weight_balance: float = 1.0
    """Weight of R_balance (paper: 1)."""

    # --- touch novelty R_touch (sec. II-A3) ------------------------------------------------
    lifetime_memory: str = "shared"
    """Whose lifetime the "first ever" bonuses (``touch_first_ever``, ``contact_first_ever``)
    count over. ``"shared"`` (default): the run's, as for the paper's one agent; one memory
    for all environments, merged across env workers (and torchrun ranks) at every PPO
    iteration boundary, so between two merges a discovery is paid at most once per worker.
    ``"per_env"``: each environment's own (a discovery can be paid once per environment, 16
    times with 16 envs); every run before issue #20 used it, and a saved config without this
    field means it."""
    touch_first_ever: float = 5.0
    """Reward for a region's first touch in the lifetime (see ``lifetime_memory``)."""
    touch_first_in_episode: float = 1.0
    """Reward for a region's first touch in the current episode."""
    touch_repeat_scale: float = 0.5
    """Repeats pay touch_repeat_scale * f_decay(c_j)."""
    decay_midpoint: float = 10.0
    """f_decay(c) = 2 / (1 + exp(decay_rate * (c - decay_midpoint))) - 1 crosses 0 here."""
    decay_rate: float = 0.5
    """Steepness of f_decay."""
    touch_count: str = "onset"
    """What c_j counts and when repeats pay. ``onset`` (default): touch events only (a touch's
    first step counts and pays; holding it costs nothing more); in the 300k pilots of issue #28
    it raised the training per-episode score from 0.20-0.24 to 0.30-0.32 (2 seeds each,
    ``results/learner/README.md``). ``step`` (the paper's literal rule, ``--preset paper``):
    every step a region is touched, so a region held for a whole episode costs about -489.
    A saved config without this field means ``step``."""

    # --- contact novelty R_geom (sec. II-A3) ------------------------------------------------
    contact_first_ever: float = 10.0
    """Reward for a (hand, region) pair's first contact in the lifetime (``lifetime_memory``)."""
    contact_first_in_episode: float = 2.0
    """Reward for a (hand, region) pair's first contact in the current episode."""

    # --- diversity milestones R_milestones (sec. II-A3) ------------------------------------
    milestone_reward: float = 5.0
    """Bonus paid once per episode per milestone crossed."""
    milestones: tuple[int, ...] = (5, 10, 15, 20, 25, 30)
    """Distinct touched regions (of 68) in the episode at which the bonus is paid."""

    # --- balance R_balance (sec. II-A3) -----------------------------------------------------
    balance_reward: float = 10.0
    """Bonus on the episode's last step when |N_L - N_R| <= balance_tolerance."""
    balance_tolerance: int = 3
    """Largest |N_L - N_R| (distinct parts of 34 touched per hand) that still pays."""
    balance_min_parts: int = 0
    """Extra condition N_L + N_R >= this (paper: none, i.e. 0; then an episode without any
    touch also pays the bonus). Set 1 or more to stop rewarding idleness."""

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
    """Environment steps (all environments) of stage 1, fixed initial pose (paper: 4M)."""
    random_pose_steps: int = 4_000_000
    """Environment steps of stage 2, random initial joint angles (paper: 4M). Informational:
    the last stage lasts until training ends (set total_steps = 8M for the paper's run)."""

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
        """Raise ValueError naming a wrong choice and the valid ones; normalise milestones."""
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
        self.milestones = tuple(sorted(int(m) for m in self.milestones))
