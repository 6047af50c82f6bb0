"""evaluate(): run a policy (checkpoint or baseline) under the behaviour's evaluation protocol."""

from __future__ import annotations

import copy
import json
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import torch
from tqdm import tqdm

from devlearn.ages import check_age
from devlearn.api.behavior import evaluation_stage
from devlearn.api.errors import UsageError
from devlearn.config.resolve import RunRequest, resolve_config
from devlearn.config.run_config import to_dict
from devlearn.env.behavior_env import BehaviorEnv
from devlearn.evaluation.episodes import (
    VIDEO_FPS,
    ActorPolicy,
    EpisodePlan,
    HeldPolicy,
    Players,
    Policy,
    ScriptedActions,
    UniformPolicy,
    ZeroPolicy,
    merged_results,
    merges,
    prepare_env,
)
from devlearn.evaluation.scripted_policy import ScriptedPolicy
from devlearn.training.checkpoint import LATEST, Checkpoint, is_scripted_policy

if TYPE_CHECKING:
    from devlearn.env.behavior_env import InfantFactory
    from devlearn.plugins import PluginRegistry

AGE_KEY = "infant.age_months"
"""The one ``--set`` key a checkpoint's evaluation takes: the body's age."""
POLICY_FILE = "policy.pt"
"""Name of a slimmed policy file (``devlearn slim``) in a published run folder."""
POLICIES = ("checkpoint", "zero", "random", "held_random")
"""What ``evaluate`` can run: a checkpoint's mean action, or a baseline: zero action, actions
uniform in [-1, 1] drawn afresh every step (i.i.d.), or ``held_random``: uniform actions each
held for :data:`~devlearn.evaluation.episodes.HOLD_STEPS` (8) physics steps on average (each
actuator redraws with probability 1 / HOLD_STEPS per physics step, as motor babbling does;
with a decision rate K, K / HOLD_STEPS per decision), which moves the damped limbs much
further than i.i.d. noise. All seeded by the evaluation seed."""
ACTIONS = ("mean", "sample")
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
        UsageError: It cannot be created or written.
    """
    out = Path(out_dir)
    probe = out / f".devlearn-write-test-{os.getpid()}"
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe.write_text("")
        probe.unlink()
    except OSError as exc:
        raise UsageError(f"cannot write to output folder {out}: {exc.strerror or exc}") from None
    return out


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


def make_policy(
    policy: str,
    opened: Checkpoint | ScriptedPolicy | None,
    obs: dict[str, np.ndarray],
    action_dim: int,
    seed: int,
    repeat: int,
    sample: bool,
) -> Policy:
    """The policy ``policy`` names: the checkpoint's network (built for ``obs``; torch's global
    generator, seeded with the evaluation seed, draws its initialisation and then, with
    ``sample``, its actions), a scripted policy's deterministic action, or a baseline seeded by
    the evaluation seed."""
    if policy == "zero":
        return ZeroPolicy(action_dim)
    if policy == "random":
        return UniformPolicy(action_dim, seed)
    if policy == "held_random":
        return HeldPolicy(action_dim, seed, repeat)
    assert opened is not None, "the checkpoint policy needs a checkpoint"
    if isinstance(opened, ScriptedPolicy):
        return ScriptedActions(opened)
    actor = opened.actor(obs, action_dim)
    return ActorPolicy(actor, action_dim, sample, torch.get_rng_state())


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


def available_cores() -> int:
    """The CPU cores this process may run on."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


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
    process.

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
    cores = available_cores() if cores is None else cores
    if workers is None:
        workers = cores if cores > 1 and episodes >= PARALLEL_MIN_EPISODES * cores else 0
    if envs is None:
        envs = max(1, workers * ENVS_PER_WORKER)
    envs = min(envs, episodes)
    workers = min(workers, envs) if envs > 1 else 0
    return envs, workers


def evaluate(
    behavior_name: str,
    checkpoint: str | Path | None,
    episodes: int,
    registry: PluginRegistry,
    video: str | Path | None = None,
    seed: int = 0,
    out_dir: str | Path | None = None,
    infant_factory: InfantFactory | None = None,
    progress: bool = True,
    policy: str = "checkpoint",
    start: str = "stage",
    overrides: list[str] | None = None,
    action: str = "mean",
    envs: int | None = 1,
    workers: int | None = 0,
) -> dict[str, Any]:
    """Run ``episodes`` episodes of a policy and summarise them under the evaluation protocol.

    The env uses :func:`~devlearn.api.behavior.evaluation_stage`'s options (the behaviour's
    declared protocol, or the curriculum stage where the policy trained) and
    ``behavior.evaluator(training=False)``.
    A checkpoint acts with its mean action (deterministic); the baselines ``zero`` and
    ``random`` run through exactly the same loop with the behaviour's default config.
    The episodes are those of one env playing them in order whatever ``envs`` and ``workers``
    (:mod:`devlearn.evaluation.episodes`): several envs only play them sooner.

    Args:
        behavior_name: The behaviour the checkpoint must belong to.
        checkpoint: Path of a devlearn checkpoint or policy file, a scripted policy file
            (another learner's, :mod:`~devlearn.evaluation.scripted_policy`), or a run folder
            (its ``checkpoint_latest.pt`` or ``policy.pt``); None for a baseline.
        episodes: Number of full episodes.
        registry: Plugin registry.
        video: Write an MP4 of the first episode here (needs imageio-ffmpeg).
        seed: Seed of the env's initial poses (and of the ``random`` baseline's actions).
        out_dir: Write ``eval.json`` and the evaluator's artifacts here (checked to be
            writable before any episode runs).
        infant_factory: Infant builder (tests); default the real infant.
        progress: Show a progress bar (steps, episodes) on stderr.
        policy: One of :data:`POLICIES`.
        start: One of :data:`STARTS`; other than ``stage`` it overrides the stage's
            ``random_pose`` and the infant's start.
        overrides: ``key=value`` settings of a baseline's config (``--set``), e.g. a
            calibrated detector for hand regard's baselines
            (``behavior.detector_file=runs/hr/hand_detector.json``); with a checkpoint, whose
            config is its own, only ``infant.age_months=A``: evaluate the policy in the body
            at age A (by default a checkpoint is evaluated at the age it last trained at).
        action: A checkpoint's action: ``mean`` (deterministic, the default protocol) or
            ``sample`` (drawn from the policy's distribution, as in training: a behaviour whose
            skill lives in the policy's noise shows it only so).
        envs: Envs playing episodes at once (None: automatic, see :func:`parallelism`).
        workers: Env worker processes they are split over (0: this process; None:
            automatic). With workers, ``infant_factory`` must be picklable.
    Returns:
        ``evaluator.summary()`` plus ``behavior``, ``policy``, ``checkpoint``,
        ``checkpoint_env_steps`` (x axis of ``devlearn curve``), ``training_seed``, ``config``
        (the checkpoint's, for ``devlearn report``'s grouping), ``age_months`` (the body's age,
        None: the default body), ``start`` (the start episodes took: babybench, rest or
        random), ``protocol`` (episodes, seed, start, settle steps, criteria, training steps,
        code commit), for a scripted policy ``learner`` (who trained it), and ``execution``
        (envs, workers, wall seconds: how it ran, not part of the protocol). Not part of eval.json:
        ``episode_metrics``, every episode's ``end_episode`` metrics in order, and, when files
        were written, ``written``, their paths.
    Raises:
        UsageError: Missing, corrupt or foreign checkpoint; bad policy; unwritable out_dir.
        EvalWriteError: The episodes ran but writing files failed (carries the summary).
    """
    if policy not in POLICIES:
        raise UsageError(f"unknown policy '{policy}'; valid: {', '.join(POLICIES)}")
    if start not in STARTS:
        raise UsageError(f"unknown start '{start}'; valid: {', '.join(STARTS)}")
    if action not in ACTIONS:
        raise UsageError(f"unknown action '{action}'; valid: {', '.join(ACTIONS)}")
    if action != "mean" and policy != "checkpoint":
        raise UsageError(f"--action {action} is a checkpoint's; a baseline acts as it is named")
    if (checkpoint is None) != (policy != "checkpoint"):
        raise UsageError(
            "give a checkpoint, or a baseline policy (zero, random, held_random), not both"
        )
    ages = [o for o in overrides or [] if str(o).split("=", 1)[0].strip() == AGE_KEY]
    if checkpoint is not None and len(ages) < len(overrides or []):
        raise UsageError(
            f"--set applies to baselines only, and {AGE_KEY}: a checkpoint evaluates with "
            "its config"
        )
    out = prepare_out_dir(out_dir) if out_dir is not None else None
    opened: Checkpoint | ScriptedPolicy | None = None
    if checkpoint is not None:
        path = resolve_checkpoint(checkpoint)
        if is_scripted_policy(path):  # another learner's (devlearn.gym.save_policy)
            if action != "mean":
                raise UsageError(
                    f"--action {action}: a scripted policy ({path}) gives one deterministic "
                    "action; sampling needs a devlearn checkpoint"
                )
            opened = ScriptedPolicy.open(path, registry, behavior_name)
        else:
            opened = Checkpoint.open(path, registry, behavior_name)
        checkpoint, state, cfg = opened.path, opened.state, opened.config
        behavior = opened.behavior()
        age = _evaluated_age(ages, opened.age_months)
    else:
        # a baseline: the config a saved config without values means (the behaviour's
        # LEGACY_DEFAULTS), acting at the decision rate a new run of the behaviour would use
        state = {}
        fresh = resolve_config(RunRequest(behavior_name), registry)
        rate = [f"env.action_repeat={fresh.env.action_repeat}"]
        request = RunRequest(behavior_name, [*rate, *(overrides or [])], saved={})
        cfg = resolve_config(request, registry)
        behavior = registry.create(behavior_name, cfg.behavior)
        age = cfg.infant.age_months
    torch.manual_seed(seed)
    threads = torch.get_num_threads()
    # A batch of one gains nothing from more threads, and several threads on a core that
    # another program uses are many times slower (measured: a 64x64 eye CNN 85 ms vs 11 ms).
    torch.set_num_threads(1)
    repeat = cfg.env.action_repeat
    began = time.monotonic()
    try:
        stage = evaluation_stage(behavior, int(state.get("env_steps", cfg.total_steps)))
        infant_start = None
        if start != "stage":
            stage = {**stage, "random_pose": start == "random"}
            if start != "random":
                infant_start = start
        elif not stage.get("random_pose") and hasattr(behavior, "eval_start"):
            # a behaviour may evaluate from another start than it trains from (hand regard's
            # eval_start); the infant was built with the training start
            infant_start = behavior.eval_start()
        envs, workers = parallelism(
            episodes, envs, workers, merges(behavior.evaluator(training=False))
        )
        with Players(behavior, envs, workers, seed, infant_factory, repeat, age) as players:
            # An env here gives the observation the network is built for and the episode
            # length: the first player in this process, else one of its own.
            env = (
                players.envs[0]
                if players.envs
                else BehaviorEnv(
                    copy.deepcopy(behavior),
                    seed,
                    infant_factory,
                    training=False,
                    action_repeat=repeat,
                    age_months=age,
                )
            )
            try:
                prepare_env(env, stage, infant_start)
                chosen = make_policy(
                    policy, opened, env.reset(), env.action_dim, seed, repeat, action == "sample"
                )
                episode_steps, step_dt = env.episode_steps, env.step_dt
            finally:
                if not players.envs:
                    env.close()
            if video is not None:
                Path(video).parent.mkdir(parents=True, exist_ok=True)
            plan = EpisodePlan(
                blocks=tuple(
                    (int(b[0]), int(b[-1]) + 1) for b in np.array_split(np.arange(episodes), envs)
                ),
                seed=seed,
                stage=stage,
                start=infant_start,
                decisions=episode_steps // repeat,
                policy=chosen,
                video=None if video is None else str(video),
                video_stride=max(1, round(1.0 / (step_dt * repeat * VIDEO_FPS))),
            )
            with tqdm(
                total=episodes * episode_steps,
                unit="step",
                disable=not progress,
                desc=f"eval {behavior_name}",
                file=sys.stderr,
                dynamic_ncols=True,
            ) as bar:
                ended = [0]

                def report(steps: int, finished: int) -> None:
                    ended[0] += finished
                    bar.set_postfix(episodes=f"{ended[0]}/{episodes}", refresh=False)
                    bar.update(steps)

                results = players.play(plan, report)
        evaluator, episode_metrics, started = merged_results(results)
        summary = evaluator.summary()
        steps = int(state.get("env_steps", 0))
        summary.update(
            behavior=behavior_name,
            policy=policy,
            checkpoint=str(checkpoint) if checkpoint is not None else None,
            checkpoint_env_steps=steps,
            training_seed=int(cfg.seed) if checkpoint is not None else None,
            config=state["config"] if checkpoint is not None else to_dict(cfg),
            age_months=age,
            start=started,
            protocol={
                "episodes": episodes,
                "seed": seed,
                "policy": policy,
                "action": action if policy == "checkpoint" else policy,
                "stage": json.loads(json.dumps(stage, default=str)),
                "start": started,
                "start_option": start,
                "settle_steps": 0,
                "action_repeat": repeat,
                "age_months": age,
                **evaluator.protocol(),
                "checkpoint_env_steps": steps,
                "code": code_version(),
            },
            execution={
                "envs": envs,
                "workers": workers,
                "wall_seconds": round(time.monotonic() - began, 1),
            },
        )
        if isinstance(opened, ScriptedPolicy):
            summary["learner"] = opened.learner  # devlearn report tells learners apart
        if out is not None:
            written = []
            try:
                (out / "eval.json").write_text(json.dumps(summary, indent=2, default=float) + "\n")
                written = [out / "eval.json", *evaluator.write_artifacts(out)]
            except OSError as exc:
                raise EvalWriteError(
                    f"evaluated, but writing to {out} failed: {exc.strerror or exc}", summary
                ) from None
            summary["written"] = [str(p) for p in written]
        summary["episode_metrics"] = episode_metrics
        return summary
    finally:
        torch.set_num_threads(threads)
