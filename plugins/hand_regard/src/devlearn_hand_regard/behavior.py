"""The hand_regard behaviour: look at your own hands (paper sec. II-B, Model II)."""

from __future__ import annotations

import copy
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from devlearn import (
    About,
    Artifacts,
    BatchedIntrinsicReward,
    Behavior,
    Curriculum,
    EpisodeHooks,
    EpisodeSpec,
    EvalProtocol,
    IntrinsicReward,
    MLPEncoder,
    NetworkSpec,
    Stage,
    UsageError,
    per_env,
)
from devlearn.api.rewards import build_reward_terms
from devlearn_hand_regard import detector_store
from devlearn_hand_regard.config import (
    APPEARANCE_CHOICES,
    BABBLING_ARMS_CHOICES,
    CRITIC_CHOICES,
    HAND_ATTRIBUTION_CHOICES,
    NOT_IN_PAPER,
    POLICY_CHOICES,
    REWARD_CHOICES,
    SCENE_CHOICES,
    START_CHOICES,
    HandRegardConfig,
)
from devlearn_hand_regard.detector import DetectorParams, HandDetector, HandFlow
from devlearn_hand_regard.evaluation import HandRegardEvaluator, paper_figures
from devlearn_hand_regard.rewards import HANDS, hand_motion

if TYPE_CHECKING:
    from devlearn import Infant, SensorEncoder

DETECTOR_FILE = "hand_detector.json"
"""Name of the calibrated detector in a run directory."""
STAGE_SHARE = 0.1
"""Share of a run each one-arm stage takes unless set (:func:`stages_as_shares`)."""
PAPER_STAGE_STEPS = (
    HandRegardConfig.left_arm_steps,
    HandRegardConfig.right_arm_steps,
    HandRegardConfig.both_arms_steps,
)
"""The paper's stages (left arm, right arm, both; sec. II-B5): the config's defaults, 175k +
175k + 1.5M physics steps (``--preset paper``)."""
DEMO_STEPS = (20_000, 20_000, 160_000)
"""``devlearn run hand_regard`` without ``--steps``: a demonstration of a few minutes on a CPU,
the paper's three stages in short (left arm, right arm, both: the shares of
:func:`stages_as_shares`); ``--preset paper`` is the paper's 175k + 175k + 1.5M.
Issue #55: 200,000 steps, because the 30,000 steps before it never saw a hand (detector 0.000
against random actions' 0.017, 100 episodes from BabyBench's start) and 200,000 see one hand
with both eyes (`results/hand_regard/i55_default_run/`)."""


def hand_features(detections: np.ndarray, masks: np.ndarray) -> np.ndarray:
    """The detector's output as the ``proprio`` policy sees it.

    Args:
        detections: (2 eyes, 2 hands) bool.
        masks: (2 eyes, 2 hands, H, W) bool, each detected hand's pixels.
    Returns:
        (16,) float32: per (eye, hand), in that order: detected (0 or 1), the mask's centre
        x and y in [-1, 1] (image centre 0; 0 when not detected) and its area as a fraction of
        the image.
    """
    eyes, hands, height, width = masks.shape
    out = np.zeros((eyes, hands, 4), dtype=np.float32)
    for e in range(eyes):
        for h in range(hands):
            if not detections[e, h]:
                continue
            ys, xs = np.nonzero(masks[e, h])
            if not len(xs):
                continue
            out[e, h] = (
                1.0,
                2.0 * (xs.mean() + 0.5) / width - 1.0,
                2.0 * (ys.mean() + 0.5) / height - 1.0,
                len(xs) / float(height * width),
            )
    return out.ravel()


ISSUE_28_LEARNER: dict[str, Any] = {
    "network.encoders": "behavior",
    "network.activation": "relu",
    "network.init": "torch",
    "network.head": "gaussian",
    "network.final_std": 0.0,
    "ppo.adam_eps": 1e-8,
    "ppo.normalize_advantage_per_mini_batch": False,
    "network.exploration_beta": 0.0,
    "ppo.full_rate_steps": 0,
}
"""The core learner as it was before issue #54 (issue #28's), which every published hand-regard
result was trained with: kept here until a rerun shows issue #54's learner does no worse (one
step size for any run length included: the paper's 1.85M too). White
exploration included: with the core's pink exploration the proprioception policy scored 0.482
[0.474, 0.490] at 614k against white's 0.516 [0.384, 0.648] (3 seeds, paired -0.034 [-0.160,
+0.092]; results/learners/i54/pink_hand_regard): not better, so hand regard keeps white."""

TRAIN_DEFAULTS: dict[str, Any] = {
    "behavior.left_arm_steps": DEMO_STEPS[0],
    "behavior.right_arm_steps": DEMO_STEPS[1],
    "behavior.both_arms_steps": DEMO_STEPS[2],
    "total_steps": sum(DEMO_STEPS),
    "ppo.entropy_coef": 0.0,
    **ISSUE_28_LEARNER,
}
"""A demonstration of a few minutes on a CPU: :data:`DEMO_STEPS`, the three stages in short
(20k + 20k + 160k = 200k steps), with the ``proprio`` policy.

The paper's run (175k + 175k + 1.5M = 1.85M steps, the eye CNN) is ``--preset paper``: many
hours of rendering on a CPU. The paper gives no PPO constants for Model II beyond the network.

The learner is the core's (issue #28's evidence: a decision every 5 physics steps, so renders
and the detector once per decision; a discount of 0.99 per decision; a fixed learning rate;
separate actor and critic), with one change this behaviour's evidence supports: no entropy
bonus (with it the spread ran away from 0.5 to 2.7-5.7 in the published runs, and issue #28's
pilot learned hand regard without one). Issue #54's changes to the core learner (flat tanh
networks, the free spread under a falling ceiling) were measured on self-touch and the two
plugins, not here: hand regard keeps issue #28's network and head, on which its published
results stand, until a rerun shows the new learner does no worse (``--set network.head=free``
etc. try it)."""

PRESETS: dict[str, dict[str, Any]] = {
    "paper": {
        "behavior.policy": "cnn",
        "behavior.critic": "same",  # the paper's critic: eye CNNs of its own
        "behavior.left_arm_steps": PAPER_STAGE_STEPS[0],
        "behavior.right_arm_steps": PAPER_STAGE_STEPS[1],
        "behavior.both_arms_steps": PAPER_STAGE_STEPS[2],
        "total_steps": sum(PAPER_STAGE_STEPS),
        # the paper's policy head and shared trunk at BabyBench's 200 Hz
        "network.head": "paper",
        "network.layout": "shared",
        "network.exploration_beta": 0.0,  # white exploration, as the paper's PPO
        "env.action_repeat": 1,
        "ppo.entropy_coef": 0.005,
        "ppo.schedule": "adaptive",
    }
}
"""``paper``: the paper's network (``behavior.policy=cnn``, the eye CNNs, for the actor and the
critic alike) and run length, 175k + 175k + 1.5M = 1.85M steps (sec. II-B5)."""


def stages_as_shares(total_steps: int) -> dict[str, Any]:
    """The stages as shares of the run, as the 614,400-step experiments had them: 10% left arm,
    10% right arm, the rest both arms (the demonstration's 200k: 20k + 20k + 160k), so that
    ``--steps N`` goes through every stage; ``--set behavior.left_arm_steps=...`` or ``--preset
    paper`` (175k + 175k + 1.5M) keep their own."""
    one_arm = round(total_steps * STAGE_SHARE)
    return {
        "behavior.left_arm_steps": one_arm,
        "behavior.right_arm_steps": one_arm,
        "behavior.both_arms_steps": total_steps - 2 * one_arm,
    }


def paper_results(config: dict[str, Any]) -> tuple[str, dict[str, float]] | None:
    """The paper's visibility (Table III, its reward, 1.85M steps), whatever the run's."""
    return paper_figures()


def eyes_and_view(infant: Infant) -> np.ndarray:
    """``devlearn eval --video`` frame: left eye, right eye (64x64 shown 4x), third person.

    Returns:
        (256, 896, 3) uint8.
    """
    eyes = np.asarray(infant.eyes()).repeat(4, axis=1).repeat(4, axis=2)  # (2, 256, 256, 3)
    return np.concatenate([eyes[0], eyes[1], infant.render_view(384, 256)], axis=1)


class HandRegard(Behavior):
    """Hand regard: keep your hands in view of both eyes, from intrinsic visual rewards.

    Before training, motor babbling discovers what the hands look like (:meth:`prepare`). Each
    step the calibrated detector counts the hands in both 64x64 eye images and optical flow
    measures their motion; rewards follow the paper (sec. II-B4) plus an optional bilateral
    term. The scene is BabyBench's (``config.scene``; the instance's :attr:`scene`), every
    episode from BabyBench's start (``config.start``). Observations (``config.policy``):
    ``proprio``: ``proprioception`` (P,) float32 and ``hands_seen`` (16,) float32, the
    detector's output (:func:`hand_features`); ``cnn`` (the paper's): ``left_eye`` and
    ``right_eye`` (64, 64, 3) uint8 and ``proprioception``. Curriculum: left arm only, right
    arm only, then both (sec. II-B5).
    """

    name = "hand_regard"
    scene = "sitting_babybench"
    """The default scene; an instance uses ``config.scene`` (old runs: ``sitting``)."""
    config_class = HandRegardConfig
    about = About(
        description="Look at your own hands: babbling-calibrated hand detector, visual rewards",
        headline_metric="average",
        train_defaults=TRAIN_DEFAULTS,
        presets=PRESETS,
        run_length_defaults=stages_as_shares,
        paper_results=paper_results,
    )

    def __init__(self, config: HandRegardConfig | None = None) -> None:
        super().__init__(config)
        self.scene = self.config.scene  # the env builds the infant in this scene
        self._detector: HandDetector | None = None
        self.hooks = ArmsAndFrames(self)
        """This environment's episode state and hooks (:class:`ArmsAndFrames`)."""

    def __getstate__(self) -> dict[str, Any]:
        # Travel light to worker processes: no previous frame. The detector travels (its
        # calibrated parameters, a few numbers): a policy file's stored detector has no file
        # to be reloaded from there (devlearn eval --workers).
        state = dict(self.__dict__)
        hooks = copy.copy(self.hooks)
        hooks.flow = HandFlow()
        state.update(hooks=hooks)
        return state

    # --- set-up -----------------------------------------------------------------------------
    def episode(self) -> EpisodeSpec:
        """Proprioception and the eyes; the infant's appearance (``config.appearance``: skin
        or mittens) and how its episodes start (``config.start``); renders and the detector
        once per decision, not on every physics step (``env.action_repeat``); the hooks of
        :class:`ArmsAndFrames`.

        Raises:
            UsageError: A scene, start, appearance or policy not among the valid ones.
        """
        cfg = self.config
        _check_choice("appearance", cfg.appearance, APPEARANCE_CHOICES)
        _check_choice("scene", cfg.scene, SCENE_CHOICES)
        _check_choice("start", cfg.start, START_CHOICES)
        _check_choice("eval_start", cfg.eval_start, START_CHOICES)
        _check_choice("policy", cfg.policy, POLICY_CHOICES)
        _check_choice("critic", cfg.critic, CRITIC_CHOICES)
        _check_choice("babbling_arms", cfg.babbling_arms, BABBLING_ARMS_CHOICES)
        _check_choice("hand_attribution", cfg.hand_attribution, HAND_ATTRIBUTION_CHOICES)
        self.scene = cfg.scene  # the config may have changed since __init__
        return EpisodeSpec(
            senses=("proprioception", "eyes"),
            infant_options={"appearance": cfg.appearance, "start": cfg.start},
            facts_every_physics_step=False,
            hooks=self.hooks,
        )

    def artifacts(self) -> DetectorArtifacts:
        """The calibrated detector (:class:`DetectorArtifacts`)."""
        return DetectorArtifacts(self)

    @property
    def detector(self) -> HandDetector:
        """The calibrated detector (loaded from ``config.detector_file`` on first use)."""
        if self._detector is None:
            params = None
            if self.config.detector_file:
                params = read_detector_file(self.config.detector_file)
            else:
                warnings.warn(
                    "hand_regard: no calibrated hand detector (config.detector_file is empty); "
                    "call prepare(run_dir) first. Nothing will be detected.",
                    stacklevel=2,
                )
            self._detector = self._make_detector(params)
        return self._detector

    def _make_detector(self, params: DetectorParams | None) -> HandDetector:
        """The detector of ``params`` telling the hands apart as ``config.hand_attribution``
        says (``visibility`` needs a detector calibrated since issue #39; an older one warns
        and attributes by position).

        Raises:
            UsageError: An unknown ``config.hand_attribution``.
        """
        _check_choice("hand_attribution", self.config.hand_attribution, HAND_ATTRIBUTION_CHOICES)
        return HandDetector(
            params,
            attribution=self.config.hand_attribution,
            pair_blobs=self.config.contingency_pairs,
        )

    # --- observations (one environment each: its previous frame and arm mask are its own) ---
    @per_env
    def facts(self, infant: Infant) -> dict[str, Any]:
        """Detect the hands and their motion once per step.

        Returns:
            ``eyes`` (2, H, W, 3) uint8; ``hand_detections`` (2 eyes, 2 hands) bool;
            ``hand_masks`` (2 eyes, 2 hands, H, W) bool, each detected hand's pixels;
            ``hand_flow`` (2, 2) summed flow magnitude and ``hand_pixels`` (2, 2) pixel counts
            (see :class:`HandFlow`); ``hand_count`` int; ``image_width`` int; ``motion`` float,
            m_t over both hands; ``proprioception`` (P,) float32; ``view_prior`` (2 eyes,
            2 hands) P(eye sees hand | posture) or None (the detector's visibility model).
        """
        eyes = infant.eyes()
        # The posture tells which blob is which hand (the position model babbling learned);
        # in a one-arm stage the other arm hangs still, out of view, so a blob is the moving
        # arm's hand (the infant knows which arm it moves).
        proprioception = np.asarray(infant.proprioception(), dtype=np.float32)
        view_prior = self.detector.view_prior(proprioception)  # once: attribution and rewards
        detections, masks = self.detector.detect(
            eyes, proprioception, self.hooks.moving_hands, view_prior=view_prior
        )
        flow, pixels = self.hooks.flow.update(eyes, masks)
        facts = {
            "eyes": eyes,
            "hand_detections": detections,
            "hand_masks": masks,
            "hand_flow": flow,
            "hand_pixels": pixels,
            "hand_count": int(detections.sum()),
            "image_width": int(eyes.shape[2]),
            "proprioception": proprioception,
            "view_prior": view_prior,
        }
        facts["motion"] = hand_motion(facts, [0, 1])
        return facts

    @per_env
    def observe(self, infant: Infant, facts: dict[str, Any]) -> dict[str, np.ndarray]:
        """``config.policy`` ``proprio``: ``proprioception`` and ``hands_seen`` (16,);
        ``cnn``: ``left_eye``, ``right_eye`` (H, W, 3) uint8 and ``proprioception``, and
        ``hands_seen`` for an asymmetric critic (``config.critic`` ``proprio``)."""
        proprioception = facts.get("proprioception")
        if proprioception is None:
            proprioception = np.asarray(infant.proprioception(), dtype=np.float32)
        if self.config.policy == "proprio":
            features = hand_features(facts["hand_detections"], facts["hand_masks"])
            return {"proprioception": proprioception, "hands_seen": features}
        eyes = facts["eyes"]
        obs = {"left_eye": eyes[0], "right_eye": eyes[1], "proprioception": proprioception}
        if self.config.critic == "proprio":
            obs["hands_seen"] = hand_features(facts["hand_detections"], facts["hand_masks"])
        return obs

    def network(self) -> NetworkSpec:
        """``config.policy``: ``cnn``, the paper's Model II network (sec. II-B3); ``proprio``,
        the same proprioception MLP beside a small MLP on the detector's output.

        The paper's eye CNN ends in global average pooling: its 256 features say what is in
        view, not where in the image, so a policy that must centre a hand learns that from
        proprioception alone. NetworkSpec checks the spread settings. Under ``cnn`` the actor
        sees every observation but ``hands_seen``; the critic sees what the actor sees, or
        (``critic=proprio``) proprioception and ``hands_seen`` alone.
        """
        cfg = self.config
        _check_choice("policy", cfg.policy, POLICY_CHOICES)
        _check_choice("critic", cfg.critic, CRITIC_CHOICES)
        _check_choice("babbling_arms", cfg.babbling_arms, BABBLING_ARMS_CHOICES)
        _check_choice("hand_attribution", cfg.hand_attribution, HAND_ATTRIBUTION_CHOICES)
        if cfg.policy == "proprio":
            return NetworkSpec(
                encoders={
                    "proprioception": MLPEncoder(tuple(cfg.proprioception_dims)),
                    "hands_seen": MLPEncoder((32,)),
                },
                fusion_dims=(cfg.fusion_dim,),
                trunk_dims=(),
                init_std=cfg.init_std,
                max_std=cfg.max_std,
                normalize=("proprioception",),
                share=True,
            )
        from devlearn_hand_regard.encoders import EyeCNNEncoder  # torch: only to build networks

        eye = EyeCNNEncoder()
        encoders: dict[str, SensorEncoder] = {
            "left_eye": eye,
            "right_eye": eye,
            "proprioception": MLPEncoder(tuple(cfg.proprioception_dims)),
        }
        if cfg.critic == "proprio":  # the asymmetric critic's view of the detector
            encoders["hands_seen"] = MLPEncoder((32,))
        actor = ("left_eye", "right_eye", "proprioception")
        return NetworkSpec(
            actor=actor,
            critic=("proprioception", "hands_seen") if cfg.critic == "proprio" else actor,
            encoders=encoders,
            fusion_dims=(cfg.fusion_dim,),  # 256 + 256 + 64 = 576 -> 256 (sec. II-B3)
            trunk_dims=(),  # the paper's heads sit directly on the fused features
            init_std=cfg.init_std,
            max_std=cfg.max_std,
            # Joint angles, velocities and torques have mixed scales: running standardisation.
            normalize=("proprioception",),
            share=True,  # one fused representation feeds policy and value heads (Model II)
        )

    # --- rewards, actions, curriculum -------------------------------------------------------
    def reward_terms(self) -> list[IntrinsicReward | BatchedIntrinsicReward]:
        """The config's ``rewards``: the paper's three terms, plus our terms
        (:data:`NOT_IN_PAPER`) when ``config.reward`` is ``bilateral``; zero-weight terms are
        left out.

        Raises:
            UsageError: ``config.reward`` is not one of :data:`REWARD_CHOICES`.
        """
        cfg = self.config
        _check_choice("reward", cfg.reward, REWARD_CHOICES)
        chosen = {
            name: term
            for name, term in cfg.rewards.items()
            if not (cfg.reward == "paper" and name in NOT_IN_PAPER)
        }
        return [t for t in build_reward_terms(chosen) if t.weight != 0.0]

    def curriculum(self) -> Curriculum:
        """Left arm, right arm, both arms (paper sec. II-B5: ~175k + ~175k + ~1.5M steps)."""
        cfg = self.config
        return Curriculum(
            [
                Stage("left_arm", cfg.left_arm_steps, {"active_arms": ["left"]}),
                Stage("right_arm", cfg.right_arm_steps, {"active_arms": ["right"]}),
                Stage("both_arms", None, {"active_arms": ["left", "right"]}),
            ]
        )

    def evaluation(self) -> EvalProtocol:
        """The detector's and the ground truth's visibility (:class:`HandRegardEvaluator`);
        video frames with both eyes (:func:`eyes_and_view`); both arms, every episode from
        ``config.eval_start``, also the infant's start when ``--start`` is ``stage``:
        ``babybench`` (the default,
        the paper-comparable protocol: the settled state and 10 seeded random-action steps,
        so the deterministic policy's episodes differ) or ``random`` (``random_pose``: head
        and arm joints uniform in their ranges, toys placed at random; runs before issue #29
        were evaluated this way)."""
        return EvalProtocol(
            evaluator=lambda training: HandRegardEvaluator(ground_truth=not training),
            stage={"active_arms": list(HANDS), "random_pose": self.config.eval_start == "random"},
            start=self.config.eval_start,
            render_frame=eyes_and_view,
        )


class ArmsAndFrames(EpisodeHooks):
    """One environment's episode state, kept by its hooks: the previous eye frame (optical
    flow), the arm actuator groups, and the hands whose arms the stage moves.

    Args:
        behavior: The environment's behaviour (its detector's blob tracks end with an episode).
    """

    def __init__(self, behavior: HandRegard) -> None:
        self.behavior = behavior
        self.flow = HandFlow()
        self.moving_hands = [0, 1]
        """The hands whose arms the stage moves (:meth:`process_action`)."""
        self.arm_actuators: dict[str, np.ndarray] | None = None

    def on_episode_start(self, infant: Infant, rng: np.random.Generator) -> None:
        """A new episode: forget the previous frame (no motion across episodes) and read the
        arm actuator groups that :meth:`process_action` masks."""
        self.flow.reset()
        detector = self.behavior._detector
        if detector is not None:  # the contingency rule's blob tracks end with the episode
            detector.reset()
        self.arm_actuators = {
            side: np.asarray(infant.actuator_groups[f"{side}_arm"]) for side in HANDS
        }

    def process_action(self, action: np.ndarray, stage: dict[str, Any]) -> np.ndarray:
        """Zero the actions of the arm the stage switches off (paper sec. II-B5).

        Args:
            action: (17,) in [-1, 1].
            stage: Stage options with ``active_arms``.
        Returns:
            (17,) action, inactive arm's actuators (shoulder, elbow, wrist) set to 0.
        """
        arms = stage.get("active_arms", HANDS)
        self.moving_hands = [i for i, side in enumerate(HANDS) if side in arms]
        inactive = [side for side in HANDS if side not in arms]
        if not inactive:
            return action
        if self.arm_actuators is None:
            raise RuntimeError(
                "hand_regard: process_action before on_episode_start(); the arm "
                "actuator groups are read from the infant at reset"
            )
        action = np.array(action, copy=True)
        for side in inactive:
            action[self.arm_actuators[side]] = 0.0
        return action


class DetectorArtifacts(Artifacts):
    """Hand regard's calibrated detector: made before training, carried by policy files.

    Args:
        behavior: The behaviour whose ``config.detector_file`` and detector it sets.
    """

    def __init__(self, behavior: HandRegard) -> None:
        self.behavior = behavior

    def prepare(self, run_dir: Path) -> None:
        """Reuse ``run_dir/hand_detector.json`` (a resumed run), else copy the detector
        ``config.detector_file`` names (one calibration shared by several runs), else
        calibrate one by motor babbling; either way the run folder holds its detector. A
        given detector is used as it is: one calibrated before issue #39 has no visibility
        model and attributes by position (it warns); ``python -m devlearn_hand_regard.measure
        --detector OLD --save NEW`` gives it one.

        Sets ``config.detector_file`` to the file's absolute path.

        Raises:
            UsageError: ``config.detector_file`` names a missing file.
        """
        behavior = self.behavior
        path = Path(run_dir) / DETECTOR_FILE
        given = behavior.config.detector_file
        if not path.exists() and given:
            if not Path(given).exists():
                raise UsageError(
                    f"hand_regard: behavior.detector_file {given} does not exist; give a "
                    "detector JSON (e.g. a run's hand_detector.json) or leave it empty to "
                    "calibrate by babbling"
                )
            read_detector_file(given).save(path)
        elif not path.exists():
            detector_store.calibrate_by_babbling(behavior.config).save(path)
        behavior.config.detector_file = str(path.resolve())
        behavior._detector = None

    def policy_artifacts(self) -> dict[str, Any]:
        """The calibrated detector's parameters (policy files carry them: no path to break)."""
        behavior = self.behavior
        if behavior._detector is None and not behavior.config.detector_file:
            return {}
        params = behavior.detector.params
        return {} if params is None else {"hand_detector": detector_store.as_artifact(params)}

    def load_policy_artifacts(self, artifacts: dict[str, Any], folder: Path) -> None:
        """Use the detector stored in the checkpoint, else find ``config.detector_file``.

        A file missing where the config says (an absolute path from the machine that trained
        it, or a relocated run folder) is looked for by name in the checkpoint's folder and
        the folder above it; ``config.detector_file`` is updated to the file found.

        Raises:
            UsageError: Neither stored nor found.
        """
        behavior = self.behavior
        stored = artifacts.get("hand_detector")
        if stored is not None:
            try:
                params = DetectorParams.from_dict(stored, source="the checkpoint's hand detector")
            except ValueError as err:
                raise UsageError(f"hand_regard: {err}") from None
            behavior._detector = behavior._make_detector(params)
            return
        name = behavior.config.detector_file
        if not name:
            return  # uncalibrated run: nothing is detected (the detector property warns)
        behavior.config.detector_file = str(detector_store.find_file(name, Path(folder)))
        behavior._detector = None


def _check_choice(key: str, value: str, choices: tuple[str, ...]) -> None:
    if value not in choices:
        raise UsageError(
            f"hand_regard: unknown behavior.{key} '{value}'; valid: {', '.join(choices)}"
        )


def read_detector_file(path: str) -> DetectorParams:
    """The detector ``behavior.detector_file`` names, every value checked
    (:meth:`DetectorParams.load`).

    Raises:
        UsageError: One line naming ``behavior.detector_file``, the file and the cause
            (missing, not a regular file, not JSON, nested too deeply, a value no calibration
            writes: a NaN area, an empty or NaN colour box list...).
    """
    try:
        return DetectorParams.load(path)
    except (UsageError, ValueError) as err:
        reason = str(err).removeprefix(f"{path}: ")
        raise UsageError(f"hand_regard: behavior.detector_file {path}: {reason}") from None
