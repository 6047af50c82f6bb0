"""An evaluation (``devlearn eval``): a policy (checkpoint or baseline) played under the
behaviour's evaluation protocol, as a request (:class:`EvalRequest`) and its steps
(:class:`Evaluation`)."""

from __future__ import annotations

import copy
import json
import os
import subprocess
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import torch
from tqdm import tqdm

from devlearn.ages import check_age
from devlearn.api.behavior import evaluation_stage
from devlearn.api.errors import UsageError
from devlearn.config.resolve import RunRequest, resolve_config
from devlearn.config.run_config import RunConfig
from devlearn.cores import available_cores
from devlearn.env.behavior_env import BehaviorEnv
from devlearn.env.rendering import check_senses_render, require_rendering
from devlearn.env.settings import EnvSettings
from devlearn.evaluation.episodes import (
    VIDEO_FORMATS,
    VIDEO_FPS,
    EpisodePlan,
    Players,
    SlotResult,
    merged_results,
    prepare_env,
)
from devlearn.evaluation.policy import BASELINES, Baseline, CheckpointPolicy, Policy, batch_of_one
from devlearn.evaluation.scripted_policy import ScriptedPolicy, sampling_refused
from devlearn.files import (
    NotARegularFileError,
    check_out_file,
    check_replaceable,
    write_text_atomically,
)
from devlearn.timing import decision_rate_error, physics_steps
from devlearn.training.checkpoint import LATEST, is_scripted_policy

if TYPE_CHECKING:
    from devlearn.api.behavior import Behavior, Evaluator
    from devlearn.env.behavior_env import InfantFactory
    from devlearn.plugins import PluginRegistry

AGE_KEY = "infant.age_months"
"""The one ``--set`` key a checkpoint's evaluation takes: the body's age."""
POLICY_FILE = "policy.pt"
"""Name of a slimmed policy file (``devlearn slim``) in a published run folder."""
POLICIES = ("checkpoint", *BASELINES)
"""What an evaluation can run (:mod:`devlearn.evaluation.policy`): a checkpoint's (or scripted
policy's) action, or a baseline: zero action, actions uniform in [-1, 1] drawn afresh every
step (i.i.d.), or ``held_random``: uniform actions each held for
:data:`~devlearn.evaluation.policy.HOLD_STEPS` (8) physics steps on average (each
actuator redraws with probability 1 / HOLD_STEPS per physics step, as motor babbling does;
with a decision rate K, K / HOLD_STEPS per decision), which moves the damped limbs much
further than i.i.d. noise. All seeded by the evaluation seed."""
ACTIONS = ("mean", "sample", "expected_clipped")
"""How a checkpoint acts in ``evaluate``: its mean action, or one sampled from its policy."""
STARTS = ("stage", "babybench", "rest", "random")
"""Where episodes start: ``stage``, as the behaviour's evaluation stage says (self-touch:
seeded random poses; hand regard: its ``eval_start``, BabyBench's start); ``babybench``, the
scene's initial state (settled, in scenes that settle) then 10 physics steps of seeded
uniform-random actions, as every BabyBench episode starts; ``rest``, that initial state
alone, every episode (a deterministic policy then repeats one episode, so one episode is
enough: a diagnostic that asks whether a policy has the skill where it trained); ``random``,
joint angles uniform in their ranges (and toys placed at random), a generalisation test.
``devlearn.infant.starts.STARTS`` are the infant's."""
PARALLEL_MIN_EPISODES = 8
"""Episodes per core from which an automatic evaluation starts env workers: a worker's
start-up costs seconds, about ten self-touch episodes (a third of a second each on one core)."""
ENVS_PER_WORKER = 4
"""Envs per worker when ``--envs`` is automatic: a worker steps its envs together (batched
facts and reward terms), and its runs of episodes stay long enough to balance the workers."""


class EvalWriteError(UsageError):
    """Evaluating worked but writing its files failed; ``summary`` holds the results."""

    def __init__(self, message: str, summary: dict[str, Any]) -> None:
        super().__init__(message)
        self.summary = summary


def resolve_checkpoint(path: str | Path) -> Path:
    """The checkpoint file ``path`` names: the file itself, or a run folder's newest.

    Raises:
        UsageError: A folder holding neither ``checkpoint_latest.pt`` nor ``policy.pt``.
    """
    path = Path(path)
    if not path.is_dir():
        return path
    for name in (LATEST, POLICY_FILE):
        if (path / name).is_file():
            return path / name
    raise UsageError(
        f"--checkpoint {path} is a folder without {LATEST} or {POLICY_FILE}; "
        "a checkpoint file (.pt) is expected"
    )


def prepare_out_dir(out_dir: str | Path) -> Path:
    """Create ``out_dir`` and check that files can be written there (before any episode runs).

    Raises:
        UsageError: It cannot be created or written, or its ``eval.json`` is not a regular
            file (a device or FIFO, which is never replaced).
    """
    out = Path(out_dir)
    check_replaceable(out / "eval.json")
    probe = out / f".devlearn-write-test-{os.getpid()}"
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe.write_text("")
        probe.unlink()
    except OSError as exc:
        raise UsageError(f"cannot write to output folder {out}: {exc.strerror or exc}") from None
    return out


def check_video(video: str | Path) -> None:
    """Refuse a ``--video`` path that cannot take a video, before any episode runs: an
    extension not in :data:`~devlearn.evaluation.episodes.VIDEO_FORMATS`, a folder, a device or
    FIFO, a place where no file can be created; or no ffmpeg to encode it.

    Raises:
        UsageError: One line naming the problem.
    """
    import imageio_ffmpeg

    check_out_file(Path(video), "--video", tuple(VIDEO_FORMATS), parents=True)
    try:
        imageio_ffmpeg.get_ffmpeg_exe()
    except RuntimeError as exc:
        raise UsageError(f"--video needs ffmpeg: {' '.join(str(exc).split())}") from None


def code_version() -> dict[str, Any]:
    """The git commit of the devlearn code that runs (``commit`` None outside a git checkout).

    Returns:
        ``{"commit": sha or None, "dirty": bool or None}``; dirty: tracked Python files
        differ from the commit (so the code that ran is not exactly the commit's).
    """
    root = Path(__file__).resolve().parents[2]
    try:
        sha = subprocess.run(
            ["git", "rev-parse", "HEAD"],
            cwd=root,
            capture_output=True,
            text=True,
            timeout=10,
            check=True,
        ).stdout.strip()
        status = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no", "--", "*.py"],
            cwd=root,
            capture_output=True,
            text=True,
            timeout=10,
            check=True,
        ).stdout
    except (OSError, subprocess.SubprocessError):
        return {"commit": None, "dirty": None}
    return {"commit": sha, "dirty": bool(status.strip())}


def _evaluated_age(overrides: list[str], trained: float | None) -> float | None:
    """The age a checkpoint is evaluated at: the last ``infant.age_months=A`` given (``null``:
    the default body), else the age it last trained at."""
    if not overrides:
        return trained
    value = str(overrides[-1]).split("=", 1)[1].strip()
    if value.lower() in ("null", "none", ""):
        return None
    try:
        return check_age(float(value))
    except ValueError as err:
        message = str(err) if "months" in str(err) else f"{AGE_KEY} must be a number, got {value!r}"
        raise UsageError(message) from None


def paying_workers(episodes: int, workers: int) -> int:
    """The env workers that repay their start-up for ``episodes`` episodes, at most
    ``workers``: one per :data:`PARALLEL_MIN_EPISODES` episodes, and none where that leaves one
    (a lone worker only adds its start-up and round trips to one process's work). ``devlearn
    eval`` asks no more of :func:`parallelism`, so that asking for more workers never makes a
    small evaluation slower (issue #55); the API keeps what it is asked (tests of the worker
    path use few episodes)."""
    workers = min(workers, episodes // PARALLEL_MIN_EPISODES)
    return workers if workers > 1 else 0


def parallelism(
    episodes: int,
    envs: int | None,
    workers: int | None,
    merges: bool,
    cores: int | None = None,
) -> tuple[int, int]:
    """How many envs (slots) play the episodes and in how many worker processes.

    Automatic (None): one worker per core this process may use from
    :data:`PARALLEL_MIN_EPISODES` episodes per core on (fewer would not repay a worker's
    start-up), else none; :data:`ENVS_PER_WORKER` envs per worker, one without workers. There
    are never more envs than episodes nor more workers than envs; one env plays in this
    process. (``devlearn eval`` also caps workers it is asked for: :func:`paying_workers`.)

    Raises:
        UsageError: Several envs asked of a behaviour whose evaluator does not merge.
    """
    if not merges:
        if (envs or 1) > 1 or (workers or 0) > 0:
            raise UsageError(
                "this behaviour's evaluator does not merge the episodes of several envs "
                "(Evaluator.merge): evaluate it with --envs 1 --workers 0"
            )
        return 1, 0
    cores = len(available_cores()) if cores is None else cores
    if workers is None:
        workers = cores if cores > 1 and episodes >= PARALLEL_MIN_EPISODES * cores else 0
    if envs is None:
        envs = max(1, workers * ENVS_PER_WORKER)
    envs = min(envs, episodes)
    workers = min(workers, envs) if envs > 1 else 0
    return envs, workers


@dataclass(frozen=True)
class EvalRequest:
    """What ``devlearn eval`` evaluates and under which protocol: every input of an evaluation,
    checked when made (a bad value is refused in one line naming the valid ones).

    Attributes:
        behavior: The behaviour the checkpoint must belong to.
        checkpoint: Path of a devlearn checkpoint or policy file, a scripted policy file
            (another learner's, :mod:`~devlearn.evaluation.scripted_policy`), or a run folder
            (its ``checkpoint_latest.pt`` or ``policy.pt``); None for a baseline.
        policy: One of :data:`POLICIES` (``checkpoint`` with a checkpoint, else a baseline).
        episodes: Number of full episodes, at least 1.
        seed: Seed of the env's initial poses (and of a baseline's or sampling policy's draws).
        start: One of :data:`STARTS`; other than ``stage`` it overrides the stage's
            ``random_pose`` and the infant's start.
        action: One of :data:`ACTIONS`, a checkpoint's: ``mean`` (deterministic, the default
            protocol), ``sample`` (drawn from the policy's distribution, as in training: a
            behaviour whose skill lives in the policy's noise shows it only so) or
            ``expected_clipped`` (deterministic: the action the env applies on average when
            the policy samples, ``E[clip(mean + std * noise, -1, 1)]``; a mean past the bounds
            plays them only as often as training's samples did, issue #40's seed 1).
        overrides: ``key=value`` settings of a baseline's config (``--set``), e.g. a
            calibrated detector for hand regard's baselines
            (``behavior.detector_file=runs/hr/hand_detector.json``); with a checkpoint, whose
            config is its own, only ``infant.age_months=A``: evaluate the policy in the body
            at age A (by default a checkpoint is evaluated at the age it last trained at).
        envs: Envs playing episodes at once (None: automatic, see :func:`parallelism`).
        workers: Env worker processes they are split over (0: this process; None: automatic).
        session: Play every episode as one session of this many simulated seconds, without a
            reset inside (``--session 300 --start rest``: the 5-minute sessions from rest that
            infant studies code); None: the behaviour's episodes (5 s). Recorded as
            ``protocol.session_s``; the per-episode figures are then per session.
        video: Write the first episode as a video here (MP4, or another of
            :data:`~devlearn.evaluation.episodes.VIDEO_FORMATS`; checked before any episode
            runs). A video that cannot be written does not lose the evaluation.
        out_dir: Write ``eval.json`` and the evaluator's artifacts here (checked to be
            writable before any episode runs); None: write nothing.
    """

    behavior: str
    checkpoint: str | Path | None = None
    policy: str = "checkpoint"
    episodes: int = 10
    seed: int = 0
    start: str = "stage"
    action: str = "mean"
    overrides: tuple[str, ...] = ()
    envs: int | None = 1
    workers: int | None = 0
    session: float | None = None
    video: str | Path | None = None
    out_dir: str | Path | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "overrides", tuple(str(o) for o in self.overrides))
        if self.policy not in POLICIES:
            raise UsageError(f"unknown policy '{self.policy}'; valid: {', '.join(POLICIES)}")
        if self.start not in STARTS:
            raise UsageError(f"unknown start '{self.start}'; valid: {', '.join(STARTS)}")
        if self.action not in ACTIONS:
            raise UsageError(f"unknown action '{self.action}'; valid: {', '.join(ACTIONS)}")
        if self.action != "mean" and self.policy != "checkpoint":
            raise UsageError(
                f"--action {self.action} is a checkpoint's; a baseline acts as it is named"
            )
        if (self.checkpoint is None) != (self.policy != "checkpoint"):
            raise UsageError(
                "give a checkpoint, or a baseline policy (zero, random, held_random), not both"
            )
        if self.checkpoint is not None and len(self.ages) < len(self.overrides):
            raise UsageError(
                f"--set applies to baselines only, and {AGE_KEY}: a checkpoint evaluates with "
                "its config"
            )
        for name, value, least in (
            ("episodes", self.episodes, 1),
            ("seed", self.seed, 0),
            ("envs", self.envs, 1),
            ("workers", self.workers, 0),
        ):
            if value is not None and value < least:
                raise UsageError(f"--{name} must be at least {least}, got {value}")
        if self.session is not None and not self.session > 0:
            raise UsageError(f"--session must be above 0 seconds, got {self.session}")

    @property
    def ages(self) -> list[str]:
        """The ``infant.age_months=A`` items of :attr:`overrides`, in order."""
        return [o for o in self.overrides if o.split("=", 1)[0].strip() == AGE_KEY]


@dataclass
class EvalSubject:
    """What is evaluated, opened and settled once: the policy and the body's age.

    Attributes:
        policy: The policy (a checkpoint, a scripted policy or a baseline).
        age_months: The body's age the episodes play at (None: the default body).
    """

    policy: Policy
    age_months: float | None

    @property
    def behavior(self) -> Behavior:
        """The policy's behaviour, built under :attr:`config` (with a file's artifacts)."""
        return self.policy.behavior()

    @property
    def config(self) -> RunConfig:
        """The policy's config: a file's own, or a baseline's (resolved once)."""
        return self.policy.config

    @property
    def trained_steps(self) -> int:
        """The policy's training steps (0: a baseline, or a file that does not say)."""
        return self.policy.env_steps or 0

    @property
    def stage_steps(self) -> int:
        """Where in its curriculum the policy is judged: a checkpoint where its training
        ended, a baseline where a run of its config would end (``total_steps``)."""
        steps = self.policy.env_steps
        return int(self.config.total_steps) if steps is None else steps


@dataclass(frozen=True)
class EvalConditions:
    """Where and how the episodes play, settled from the request and the subject.

    Attributes:
        stage: The evaluation stage's options (:func:`~devlearn.api.behavior.evaluation_stage`,
            ``random_pose`` set by a ``--start`` other than ``stage``).
        infant_start: The infant start to set (``babybench``, ``rest``), or None: the
            infant's own (where it trained).
        envs: Envs playing the episodes (slots).
        workers: Env worker processes (0: this process).
        settings: The envs' settings: the checkpoint's decision rate and motor noise, a
            session's length.
    """

    stage: dict[str, Any]
    infant_start: str | None
    envs: int
    workers: int
    settings: EnvSettings = EnvSettings()


def default_out_dir(request: EvalRequest) -> Path:
    """Where ``devlearn eval`` writes without ``--out``: ``CHECKPOINT_DIR/eval`` (the
    checkpoint resolved, :func:`resolve_checkpoint`), a baseline's ``eval_BEHAVIOR_POLICY``
    here; an evaluation at another age goes beside the others (``eval_A_months``), not over
    them."""
    at = f"_{request.ages[-1].split('=', 1)[1].strip()}_months" if request.ages else ""
    if request.checkpoint is not None:
        return resolve_checkpoint(request.checkpoint).parent / f"eval{at}"
    return Path(f"eval_{request.behavior}_{request.policy}{at}")


def baseline_config(
    behavior_name: str, overrides: Sequence[str], registry: PluginRegistry
) -> RunConfig:
    """A baseline's config, resolved once: the config a saved config without values means (the
    behaviour's ``LEGACY_DEFAULTS``), acting at the decision rate a new run of the behaviour
    would use (its fresh config's ``env.action_repeat``), then ``overrides``."""
    return resolve_config(RunRequest(behavior_name, list(overrides), baseline=True), registry)


def open_subject(request: EvalRequest, registry: PluginRegistry) -> EvalSubject:
    """Open what ``request`` evaluates: its checkpoint (or scripted policy) and behaviour, or a
    baseline's behaviour under :func:`baseline_config`.

    Raises:
        UsageError: Missing, corrupt or foreign checkpoint; a scripted policy asked to sample;
            a bad age or override.
    """
    if request.checkpoint is None:
        cfg = baseline_config(request.behavior, request.overrides, registry)
        baseline = Baseline(request.policy, cfg, registry.create(request.behavior, cfg.behavior))
        return EvalSubject(baseline, baseline.age_months)
    path = resolve_checkpoint(request.checkpoint)
    policy: Policy
    if is_scripted_policy(path):  # another learner's (devlearn.gym.save_policy)
        if request.action != "mean":
            raise sampling_refused(path, request.action)
        policy = ScriptedPolicy.open(path, registry, request.behavior)
    else:
        policy = CheckpointPolicy.open(path, registry, request.behavior)
    policy.behavior()  # built (with its artifacts) before any env is
    return EvalSubject(policy, _evaluated_age(request.ages, policy.age_months))


def evaluation_conditions(
    request: EvalRequest, subject: EvalSubject, cores: int | None = None
) -> EvalConditions:
    """The stage, infant start and parallelism ``request`` plays ``subject``'s episodes with.

    ``--start stage`` takes the evaluation stage as declared and, unless it randomises the
    pose, the behaviour's :meth:`~devlearn.api.behavior.Behavior.eval_start` (None, the
    default: the infant's own start, where the policy trained). Another ``--start`` overrides
    both.

    Raises:
        UsageError: Several envs asked of a behaviour whose evaluator does not merge; a
            session that is not a whole number of decisions.
    """
    behavior = subject.behavior
    repeat = subject.config.env.action_repeat
    if request.session is not None:  # checked for BabyBench's 5 ms step; the env checks its own
        try:
            steps = physics_steps(request.session)
        except ValueError as err:
            raise UsageError(f"--session: {err}") from None
        if error := decision_rate_error(repeat, steps):
            raise UsageError(f"--session {request.session:g}: {error}")
    stage = evaluation_stage(behavior, subject.stage_steps)
    infant_start = None
    if request.start != "stage":
        stage = {**stage, "random_pose": request.start == "random"}
        if request.start != "random":
            infant_start = request.start
    elif not stage.get("random_pose"):
        # a behaviour may evaluate from another start than it trains from (hand regard's
        # eval_start); the infant was built with the training start
        infant_start = behavior.evaluation().start
    envs, workers = parallelism(
        request.episodes,
        request.envs,
        request.workers,
        behavior.evaluation().evaluator(False).mergeable,
        cores,
    )
    settings = EnvSettings.of(subject.config.env, request.session)  # the body's motor noise too
    return EvalConditions(stage, infant_start, envs, workers, settings)


class Evaluation:
    """One evaluation of ``devlearn eval``: a request played step by step.

    :meth:`run` opens the subject (:func:`open_subject`), settles the conditions
    (:func:`evaluation_conditions`), builds the policy and the episode plan (:meth:`plan`),
    plays the episodes (:mod:`devlearn.evaluation.episodes`), measures them (:meth:`measures`:
    the evaluator's summary and the protocol record) and writes the records (:meth:`write`:
    eval.json and the evaluator's artifacts).

    Args:
        request: What to evaluate and under which protocol.
        registry: Plugin registry.
        infant_factory: Infant builder (tests); None: the real infant. With workers it must be
            picklable.
        progress: Show a progress bar (steps, episodes) on stderr.
    """

    def __init__(
        self,
        request: EvalRequest,
        registry: PluginRegistry,
        infant_factory: InfantFactory | None = None,
        progress: bool = True,
    ) -> None:
        self.request = request
        self.registry = registry
        self.infant_factory = infant_factory
        self.progress = progress

    def run(self) -> dict[str, Any]:
        """Play the episodes and summarise them under the evaluation protocol.

        A checkpoint acts with its mean action (deterministic); the baselines run through
        exactly the same loop with the behaviour's default config. The episodes are those of
        one env playing them in order whatever ``envs`` and ``workers``: several envs only
        play them sooner.

        Returns:
            :meth:`measures`, and, not part of eval.json: ``episode_metrics``, every episode's
            ``end_episode`` metrics in order, and, when files were written, ``written``, their
            paths.
        Raises:
            UsageError: Missing, corrupt or foreign checkpoint; unwritable out_dir or video.
            EvalWriteError: The episodes ran but writing files failed (carries the summary);
                a video that failed is reported so after eval.json is written.
        """
        request = self.request
        if request.video is not None:
            check_video(request.video)
            require_rendering("--video")
        out = prepare_out_dir(request.out_dir) if request.out_dir is not None else None
        subject = open_subject(request, self.registry)
        if self.infant_factory is None:  # before any env or worker renders
            check_senses_render(subject.behavior.episode().senses, subject.behavior.name)
        torch.manual_seed(request.seed)
        threads = torch.get_num_threads()
        # A batch of one gains nothing from more threads, and several threads on a core that
        # another program uses are many times slower (measured: a 64x64 eye CNN 85 ms vs 11 ms).
        torch.set_num_threads(1)
        began = time.monotonic()
        try:
            conditions = evaluation_conditions(request, subject)
            with Players(
                subject.behavior,
                conditions.envs,
                conditions.workers,
                request.seed,
                self.infant_factory,
                conditions.settings,
                subject.age_months,
            ) as players:
                plan, episode_steps = self.plan(subject, conditions, players)
                results = self.play(players, plan, episode_steps)
            evaluator, episode_metrics, started = merged_results(results)
            video_error = next((r.video_error for r in results if r.video_error), None)
            summary = self.measures(subject, conditions, evaluator, started)
            per_episode_headline(summary, episode_metrics, subject.behavior.about.headline_metric)
            policy_figures(summary, episode_metrics)
            summary["execution"] = {
                "envs": conditions.envs,
                "workers": conditions.workers,
                "wall_seconds": round(time.monotonic() - began, 1),
            }
            if subject.policy.learner is not None:  # devlearn report tells learners apart
                summary["learner"] = subject.policy.learner
            written = self.write(out, summary, evaluator) if out is not None else []
            if video_error is not None:  # the evaluation itself is kept: eval.json written
                kept = f" ({out / 'eval.json'} is written)" if out is not None else ""
                raise EvalWriteError(f"evaluated, but {video_error}{kept}", summary)
            if out is not None:
                summary["written"] = [str(p) for p in written]
            summary["episode_metrics"] = episode_metrics
            return summary
        finally:
            torch.set_num_threads(threads)

    def plan(
        self, subject: EvalSubject, conditions: EvalConditions, players: Players
    ) -> tuple[EpisodePlan, int]:
        """The policy's actions and the episode plan every slot plays, and the episode's
        physics steps.

        An env gives the observation the network is built for and the episode length: the
        first player in this process, else one of its own.
        """
        request = self.request
        repeat = subject.config.env.action_repeat
        env = (
            players.envs[0]
            if players.envs
            else BehaviorEnv(
                copy.deepcopy(subject.behavior),
                request.seed,
                self.infant_factory,
                training=False,
                age_months=subject.age_months,
                settings=conditions.settings,
            )
        )
        try:
            prepare_env(env, conditions.stage, conditions.infant_start)
            actions = subject.policy.actions(
                batch_of_one(env.reset()), env.action_dim, request.seed, request.action
            )
            episode_steps, step_dt = env.episode_steps, env.step_dt
        finally:
            if not players.envs:
                env.close()
        if request.video is not None:
            Path(request.video).parent.mkdir(parents=True, exist_ok=True)
        blocks = np.array_split(np.arange(request.episodes), conditions.envs)
        plan = EpisodePlan(
            blocks=tuple((int(b[0]), int(b[-1]) + 1) for b in blocks),
            seed=request.seed,
            stage=conditions.stage,
            start=conditions.infant_start,
            decisions=episode_steps // repeat,
            actions=actions,
            video=None if request.video is None else str(request.video),
            video_stride=max(1, round(1.0 / (step_dt * repeat * VIDEO_FPS))),
        )
        return plan, episode_steps

    def play(self, players: Players, plan: EpisodePlan, episode_steps: int) -> list[SlotResult]:
        """Play ``plan`` with ``players``, a progress bar (steps, episodes) on stderr."""
        episodes = self.request.episodes
        with tqdm(
            total=episodes * episode_steps,
            unit="step",
            disable=not self.progress,
            desc=f"eval {self.request.behavior}",
            file=sys.stderr,
            dynamic_ncols=True,
        ) as bar:
            ended = [0]

            def report(steps: int, finished: int) -> None:
                ended[0] += finished
                bar.set_postfix(episodes=f"{ended[0]}/{episodes}", refresh=False)
                bar.update(steps)

            return players.play(plan, report)

    def measures(
        self,
        subject: EvalSubject,
        conditions: EvalConditions,
        evaluator: Evaluator,
        started: str,
    ) -> dict[str, Any]:
        """The evaluator's summary, what was evaluated and the protocol record.

        Returns:
            ``evaluator.summary()`` plus ``behavior``, ``policy``, ``checkpoint``,
            ``checkpoint_env_steps`` (x axis of ``devlearn curve``), ``training_seed``,
            ``config`` (the checkpoint's, for ``devlearn report``'s grouping), ``age_months``
            (the body's age, None: the default body), ``start`` (the start episodes took:
            babybench, rest or random) and ``protocol`` (episodes, seed, start, settle steps,
            criteria, training steps, code commit).
        """
        request = self.request
        policy = subject.policy
        steps = subject.trained_steps
        summary = evaluator.summary()
        summary.update(
            behavior=request.behavior,
            policy=policy.name,
            checkpoint=str(policy.path) if policy.path is not None else None,
            checkpoint_env_steps=steps,
            training_seed=int(subject.config.seed) if policy.path is not None else None,
            config=policy.saved_config,
            age_months=subject.age_months,
            start=started,
            protocol={
                "episodes": request.episodes,
                "seed": request.seed,
                "policy": request.policy,
                "action": request.action if request.policy == "checkpoint" else request.policy,
                "stage": json.loads(json.dumps(conditions.stage, default=str)),
                "start": started,
                "start_option": request.start,
                "settle_steps": 0,
                "action_repeat": subject.config.env.action_repeat,
                "session_s": request.session,
                "age_months": subject.age_months,
                **evaluator.protocol(),
                "checkpoint_env_steps": steps,
                "code": code_version(),
            },
        )
        return summary

    def write(self, out: Path, summary: dict[str, Any], evaluator: Evaluator) -> list[Path]:
        """Write ``summary`` as ``out/eval.json`` and the evaluator's artifacts; their paths.

        Raises:
            EvalWriteError: Writing failed (it carries ``summary``).
        """
        try:
            text = json.dumps(summary, indent=2, default=float) + "\n"
            write_text_atomically(out / "eval.json", text)
            return [out / "eval.json", *evaluator.write_artifacts(out)]
        except OSError as exc:
            raise EvalWriteError(
                f"evaluated, but writing to {out} failed: {exc.strerror or exc}", summary
            ) from None
        except NotARegularFileError as exc:  # made a device or FIFO while the episodes ran
            raise EvalWriteError(f"evaluated, but {exc}", summary) from None


def per_episode_headline(
    summary: dict[str, Any], episodes: list[dict[str, float]], headline: str
) -> None:
    """Add the headline's per-episode mean, spread and 95% t-interval over ``episodes``
    (``episode_<headline>_mean``, ``_std``, ``_ci_low``, ``_ci_high``) where the evaluator
    reports none: the figure training logs under the same name
    (:func:`~devlearn.training.runner_metrics.headline_key`), for every behaviour (issue #55).
    Nothing is added where an episode lacks the figure."""
    from devlearn.api.stats import mean_ci

    if not headline or f"episode_{headline}_mean" in summary:
        return
    values = [e[headline] for e in episodes if headline in e]
    if not values or len(values) != len(episodes):
        return
    stats = mean_ci(values)
    for name in ("mean", "std", "ci_low", "ci_high"):
        summary[f"episode_{headline}_{name}"] = stats[name]


def policy_figures(summary: dict[str, Any], episodes: list[dict[str, float]]) -> None:
    """Add ``policy_figures``: the policy's own figures (``policy/...`` in every episode's metrics,
    :meth:`~devlearn.evaluation.policy.Actions.episode_figures`) averaged over the episodes:
    a network's ``mean_at_bound`` share, so that a mean sitting past the action bounds is never
    unseen (issue #54). Nothing where the policy has none (baselines, scripted policies)."""
    keys = sorted({k for e in episodes for k in e if k.startswith("policy/")})
    if keys:
        summary["policy_figures"] = {
            k.removeprefix("policy/"): float(np.mean([e[k] for e in episodes if k in e]))
            for k in keys
        }
