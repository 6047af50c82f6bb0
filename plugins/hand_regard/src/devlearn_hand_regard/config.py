"""Options of the hand_regard behaviour (paper sec. II-B), overridable as ``behavior.FIELD``."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

from devlearn.api.behavior import BehaviorConfig
from devlearn.api.rewards import RewardTermCfg
from devlearn_hand_regard.rewards import (
    BilateralBalance,
    HandCount,
    HandMotion,
    LivingPenalty,
    ReachIntoView,
)

APPEARANCE_CHOICES = ("two_colour_mittens", "mittens", "skin")
"""Valid ``appearance`` values (``devlearn.infant.scenes.APPEARANCES``)."""
REWARD_CHOICES = ("paper", "bilateral")
"""Valid ``reward`` values."""
NOT_IN_PAPER = ("bilateral_balance", "reach_into_view")
"""Reward terms ``reward=paper`` leaves out (ours, the paper's future work)."""


def hand_regard_rewards() -> dict[str, RewardTermCfg]:
    """The paper's three terms (sec. II-B4: R_t = R_hand + R_motion - 0.05) and our
    ``bilateral_balance``, weight 1 each; our ``reach_into_view`` is there at weight 0 (off:
    a pilot of issue #39, ``--set behavior.rewards.reach_into_view.weight=1``)."""
    return {
        "hand_count": RewardTermCfg(HandCount, 1.0),
        "motion": RewardTermCfg(HandMotion, 1.0),
        "living_penalty": RewardTermCfg(LivingPenalty, 1.0),
        "bilateral_balance": RewardTermCfg(
            BilateralBalance, 1.0, {"bonus": 0.25, "penalty": 0.5, "horizon": 200.0}
        ),
        "reach_into_view": RewardTermCfg(ReachIntoView, 0.0, {"bonus": 0.25, "temperature": 1.0}),
    }


SCENE_CHOICES = ("sitting_babybench", "sitting")
"""Valid ``scene`` values (``devlearn.infant.scenes.SCENES``, the sitting ones)."""
START_CHOICES = ("babybench", "rest", "random")
"""Valid ``start`` and ``eval_start`` values (``devlearn.infant.starts.STARTS``)."""
POLICY_CHOICES = ("proprio", "cnn")
"""Valid ``policy`` values."""
CRITIC_CHOICES = ("same", "proprio")
"""Valid ``critic`` values."""
BABBLING_ARMS_CHOICES = ("alternate", "both")
"""Valid ``babbling_arms`` values."""
HAND_ATTRIBUTION_CHOICES = ("visibility", "position", "contingency")
"""Valid ``hand_attribution`` values (``detector.ATTRIBUTIONS``)."""


@dataclass
class HandRegardConfig(BehaviorConfig):
    """Everything the hand_regard behaviour can be told; paper defaults unless noted."""

    LEGACY_DEFAULTS: ClassVar[dict[str, Any]] = {
        "appearance": "mittens",
        "reward": "bilateral",
        "scene": "sitting",
        "start": "rest",
        "eval_start": "random",
        "policy": "cnn",
        "babbling_arms": "both",
        "hand_attribution": "position",
        "contingency_pairs": False,
        "critic": "same",
    }
    """Values for keys a saved config lacks: runs saved before these keys existed were trained
    with mittens and the bilateral term, in the ``sitting`` scene from its rest pose, with the
    eye CNN, and evaluated from random starts, their detector telling the hands apart by
    position; they load and evaluate that way."""

    LEGACY_REWARD_KEYS: ClassVar[dict[str, str]] = {
        "hand_count_weight": "hand_count.weight",
        "motion_weight": "motion.weight",
        "living_penalty_weight": "living_penalty.weight",
        "bilateral_weight": "bilateral_balance.weight",
        "bilateral_bonus": "bilateral_balance.params.bonus",
        "bilateral_penalty": "bilateral_balance.params.penalty",
        "bilateral_horizon": "bilateral_balance.params.horizon",
    }
    """Fields of configs saved before issue #31 that now live in :attr:`rewards` (old field ->
    ``TERM.weight`` or ``TERM.params.NAME``); such a config loads with them moved there."""

    # --- the scene and how episodes start (issue #29: BabyBench's) -------------------------
    scene: str = "sitting_babybench"
    """The infant's scene: ``sitting_babybench`` (BabyBench's hand-regard scene: head pitch
    held at 0.4 rad and side tilt at 0, only the swivel free, eyes locked, arms hanging at
    the sides, so no hand is in view at the start) or ``sitting`` (the scene of runs before
    issue #29: head free and the hands raised before the eyes at rest)."""
    start: str = "babybench"
    """How training episodes start: ``babybench`` (the scene's settled state, then 10
    physics steps of uniform-random actions, as BabyBench's), ``rest`` (the settled state
    alone) or ``random`` (joint angles uniform in their ranges, toys placed at random)."""
    eval_start: str = "babybench"
    """How ``devlearn eval`` episodes start by default (``--start stage``): ``babybench``, the
    paper-comparable protocol (BabyBench evaluates from its own reset); ``random`` is the
    generalisation row (``devlearn eval --start random``)."""
    policy: str = "proprio"
    """The policy's observations: ``proprio`` (proprioception plus the detector's output, the
    hands' detections, image positions and sizes in both eyes: a small MLP that trains on a
    CPU; the reward still comes from the images, through the detector) or ``cnn`` (the
    paper's network, sec. II-B3: a CNN per eye plus the proprioception MLP; ``--preset
    paper``). The CNN ends in global average pooling, which keeps what is seen but not where
    in the image it is."""
    critic: str = "proprio"
    """What the value function (the critic, used only in training) sees under
    ``policy=cnn``: ``proprio`` (the default since issue #40), proprioception and the
    detector's output (``hands_seen``), an asymmetric critic; or ``same``, the policy's
    observations (the paper's network: the critic has eye CNNs of its own; ``--preset
    paper``). The actor keeps its network and observations either way, so the policy sees
    and acts as the paper's does; the asymmetric critic's update runs two eye CNNs instead
    of four, 1.7x faster end to end, and kept issue #29's result in issue #40's pilot
    (``results/hand_regard/README.md``). ``proprio`` needs ``network.layout=separate`` (the
    default): a shared body serves one set of observations. Under ``policy=proprio`` both
    values give the critic the policy's observations. Configs saved before the key existed
    trained with ``same``."""

    # --- the infant's look (the paper's "without manually defined skin-colors") ---------
    appearance: str = "mittens"
    """How the infant and its toys look: ``skin`` (bare hands the body's colour, as in MIMo;
    toys in the natural palette of baby blocks, red, blue, yellow, wood), ``mittens``
    (purple mittens; toys recoloured away from their hue) or ``two_colour_mittens`` (purple
    left, magenta right: the detector can learn each hand's colour; in BabyBench's scene its
    calibration does not find the right one yet, plugin README). Babbling calibrates the detector
    on the same appearance. Default mittens: on skin the colour babbling learns is the whole
    body's and the detector fires mostly on arms, legs and trunk (results/hand_regard/README.md,
    "Detector, both appearances")."""

    # --- motor babbling and calibration (sec. II-B2) -------------------------------------
    babbling_steps: int = 10_000
    """Random-action steps recorded before training to discover the hands (paper: 10,000)."""
    babbling_seed: int = 0
    """Seed of the babbling episode's random actions and initial state."""
    babbling_hold_steps: int = 25
    """Mean steps an arm's random babbling action is held (each actuator redraws independently;
    200 Hz i.i.d. noise barely moves the damped arms, so the hands would hardly move). In
    BabyBench's scene the hands hang out of view: held 25 steps (0.125 s) they swing into
    view in ~13% of babbling frames, held 8 (the runs before issue #29, in ``sitting``) ~8%."""
    babbling_arms: str = "alternate"
    """Which arms babble: ``alternate`` (one arm per babbling episode, the other hanging
    still, so the infant knows which hand it moved: in BabyBench's scene a hand rising into
    view with both arms babbling correlates with both arms' speeds and calibration cannot
    tell left from right) or ``both`` (every arm all the time: the paper's random-action
    phase, and runs before this key)."""
    babbling_head_hold_steps: int = 50
    """Mean steps a head action is held while babbling (a slow head keeps the view steady)."""
    babbling_head_scale: float = 0.3
    """Largest head action while babbling (a gentle head keeps the hands near the view)."""
    hand_attribution: str = "visibility"
    """How the detector tells the left hand from the right (both mittens have one colour):
    ``visibility`` (issue #39): each hand's visibility per eye predicted from its own arm's
    posture, learned from one-arm babbling (plugin README, "Which hand is it"; on held-out
    both-arm babbling pair precision / recall 0.95 / 0.86 against ``pixels``) or ``position``
    (the image position each hand is expected at: the rule of every run before issue #39,
    0.55 / 0.54 on the committed protocol's frames, where ``visibility`` has 0.95 / 0.93; and
    of saved configs without this key) or ``contingency`` (issue #58): a blob is credited to
    a hand only when it lies where the body's kinematics put that hand and not the other, and
    its track moves with that arm, else to no side; its ``contingency_model`` is fitted from
    the calibration babbling of a fresh run, or read from a detector file
    (``python -m devlearn_hand_regard.contingency_check fit``; plugin README)."""
    contingency_pairs: bool = True
    """``contingency`` only: two blobs in an eye, each within reach of one hand only and of
    different hands, are those hands' even where the other hand is nearer than the rule's
    margin (both hands in view beside each other; :data:`contingency.PAIR_BLOBS`). Saved
    configs without this key (issue #58's pilot) attribute without it."""
    attribution_babbling_share: float = 5.0
    """One-arm babbling recorded after calibration (seeds from ``babbling_seed + 2``), in steps
    as a share of ``babbling_steps`` (5.0: 50,000 more at the paper's 10,000; ~2 min of
    rendering on a free core), whose frames teach only the ``visibility`` attribution:
    whether the calibrated colour detector sees a hand, and which arm moved. A hand is in view
    in ~4% of babbling frames, and the postures that show it are many: on five held-out seeds
    of both-arm babbling the pair precision / recall averaged 0.83 / 0.76 from the
    calibration's 10,000 steps alone, 0.94 / 0.85 with 10,000 more, 0.95 / 0.86 with 30,000
    and with 50,000 (issue #39). 0: learn from the calibration recording only."""
    correlation_threshold: float = 0.6
    """A blob track whose motion correlates above this with the arm proprioception is a hand
    (paper: rho_k > 0.6)."""
    detector_file: str = ""
    """Calibrated detector (JSON). Set by ``prepare(run_dir)`` to ``run_dir/hand_detector.json``
    (babbling runs first if that file is missing). Empty: uncalibrated, nothing is detected."""

    # --- reward (sec. II-B4); a weight of 0 switches a term off ---------------------------
    reward: str = "bilateral"
    """Which reward: ``paper`` (the paper's exact terms: hand count, motion, living penalty;
    the terms of :data:`NOT_IN_PAPER` are left out) or ``bilateral`` (every term of
    ``rewards``, our ``bilateral_balance`` included)."""
    rewards: dict[str, RewardTermCfg] = field(default_factory=hand_regard_rewards)
    """Term name -> (class, weight, params) (:func:`hand_regard_rewards`): ``hand_count``
    (-0.1, 0.25, 0.5, 1.0, 2.0 for n_t = 0..4 detections), ``motion`` (optical flow in the hand
    regions, rewarding moderate motion), ``living_penalty`` (-0.05 per step) and
    ``bilateral_balance`` (not in the paper, its future work; only while both arms are
    active: ``bonus`` on steps where each hand is detected by at least one eye, minus
    ``penalty`` per unit of |v_left - v_right|, the gap between the hands' recent visibility,
    exponential moving averages over ``horizon`` steps) and ``reach_into_view`` (ours, off
    by default: ``bonus`` times the posture-predicted visibility of the hand less likely in
    view, a gradient toward both hands in view; both-arm stages only). A term of weight 0 is
    left out."""

    # --- curriculum (sec. II-B5) ----------------------------------------------------------
    left_arm_steps: int = 175_000
    """Stage ``left_arm``: only the left arm moves and only the left hand is rewarded."""
    right_arm_steps: int = 175_000
    """Stage ``right_arm``: only the right arm moves and only the right hand is rewarded."""
    both_arms_steps: int = 1_500_000
    """Stage ``both_arms`` (last): both arms, both hands. Sets the default run length."""

    # --- network (sec. II-B3) -------------------------------------------------------------
    proprioception_dims: tuple[int, ...] = (128, 64)
    """Two-layer proprioception MLP ending in the paper's 64 features."""
    fusion_dim: int = 256
    """Fused feature size after the 576-d concatenation (paper: 256)."""
    init_std: float = 0.5
    """Initial policy standard deviation."""
    max_std: float = 0.0
    """Upper bound on the policy's standard deviation (bounded with a sigmoid, as self-touch's
    default); 0: the unbounded softplus spread (the paper, and every hand-regard run of issue
    #19). Actions are clipped to [-1, 1], so a spread past 1 buys entropy bonus without changing
    much what the arm does: in the issue-19 runs it grew from 0.5 to ~2.7 (paper reward) over
    300k steps, and the training actions became near-random (results/hand_regard/README.md)."""
