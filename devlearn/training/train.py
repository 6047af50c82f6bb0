"""train(): config, seed, behaviour, environments, runner, learn, save."""

from __future__ import annotations

import errno
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import torch

from devlearn.api.errors import UsageError
from devlearn.config.checks import check_memory, check_out_dir, holds_run
from devlearn.config.growth import growth_schedule, start_age
from devlearn.config.resolve import (
    CONFIG_FILE,
    ResolvedRun,
    RunRequest,
    resolve_run,
    write_config_file,
)
from devlearn.config.run_config import RunConfig, to_rsl_rl
from devlearn.env import DevVecEnv, EnvSettings
from devlearn.env.rendering import check_senses_render
from devlearn.training.checkpoint import (
    LATEST,
    RESUME_KEYS,
    Checkpoint,
    check_behavior,
    check_fits,
    periodic_checkpoints,
    remove_temporaries,
    resume_checkpoint,
)
from devlearn.training.learned_rewards import LearnedRewards
from devlearn.training.loggers import logger_config
from devlearn.training.process import (
    init_distributed,
    rank_seed,
    resolve_device,
    resolve_workers,
    seed_everything,
)
from devlearn.training.run_folder import check_run_files, copy_metrics, locked, start_up
from devlearn.training.runner import DevRunner

if TYPE_CHECKING:
    from devlearn.api.behavior import Behavior
    from devlearn.env.behavior_env import InfantFactory
    from devlearn.plugins import PluginRegistry


@dataclass
class TrainResult:
    """What a finished (or resumed and finished) run reports."""

    run_dir: Path
    """The run directory."""
    env_steps: int
    """Environment steps done in total (all envs, all ranks)."""
    iterations: int
    """PPO iterations done in total."""
    last: dict[str, Any] = field(default_factory=dict)
    """The last metrics.jsonl row (mean reward, reward terms, metrics, stage...)."""
    warnings: list[str] = field(default_factory=list)
    """The learner-health warnings the run gave (:mod:`devlearn.training.health`)."""


@dataclass
class RunContext:
    """What a run's start-up settled, read by the parts it builds (one object instead of a dozen
    parameters): the checked config, where it runs and as which rank, and what it continues."""

    cfg: RunConfig
    """The run config, checked, with ``out_dir`` and ``workers`` resolved."""
    registry: PluginRegistry
    """Where its behaviour comes from."""
    run_dir: Path
    """The run folder."""
    rank: int
    """This process's rank (torchrun's ``RANK``; 0 alone)."""
    world_size: int
    """Ranks in the run (torchrun's ``WORLD_SIZE``; 1 alone)."""
    device: str
    """Torch device of the networks."""
    learned: LearnedRewards
    """The learned rewards (``curiosity``), names checked."""
    checkpoint: dict[str, Any] | None = None
    """The state it continues from (its own latest when resuming, another run's with
    ``start_from``); None: a fresh start."""
    checkpoint_path: str | Path | None = None
    """Where ``checkpoint`` was read (for messages)."""
    start_from: str | Path | None = None
    """Another run's checkpoint this new run starts from (``devlearn run --from``)."""
    infant_factory: InfantFactory | None = None
    """Infant builder for the envs (tests); None: the real infant."""
    progress: bool = True
    """Show the progress bar."""
    behavior: Behavior | None = None
    """The behaviour resolving built on ``cfg.behavior`` (:class:`ResolvedRun`); None: built
    here from the config."""


def default_run_dir(behavior_name: str) -> Path:
    """``runs/<behavior>-<YYYYmmdd-HHMMSS>``."""
    return Path("runs") / f"{behavior_name}-{time.strftime('%Y%m%d-%H%M%S')}"


def check_resumable(cfg: RunConfig, checkpoint: dict[str, Any], path: str | Path) -> None:
    """Raise UsageError unless ``checkpoint`` (at ``path``) can continue under ``cfg``: same
    behaviour, same number of environments per rank."""
    check_behavior(checkpoint, path, cfg.behavior_name)
    saved = checkpoint["env"]["ranks"][0]["envs"]
    if len(saved) != cfg.num_envs:
        raise UsageError(
            f"checkpoint has {len(saved)} envs per rank; resume with --envs {len(saved)}"
        )


def train(
    cfg: RunConfig | ResolvedRun | None,
    registry: PluginRegistry,
    *,
    resume: str | Path | None = None,
    start_from: str | Path | None = None,
    infant_factory: InfantFactory | None = None,
    progress: bool = True,
    force: bool = False,
    started: Callable[[Path], None] | None = None,
) -> TrainResult:
    """Train ``cfg.behavior_name`` with PPO; return where and how far it got.

    Args:
        cfg: The run, checked: :func:`~devlearn.config.resolve.resolve_run`'s (the config
            and the behaviour built on it, which the run trains), or
            :func:`~devlearn.config.resolve.resolve_config`'s config alone (the behaviour is
            then built again from it); with ``resume``, None reads the run's config.json.
        registry: Plugin registry (``.behavior(name)``).
        resume: A run directory to continue from its newest complete checkpoint: step counter,
            curriculum stage, reward-term state, networks and optimiser are restored.
        start_from: A checkpoint (of another run) a new run in ``cfg.out_dir`` starts from:
            networks, optimiser, step and iteration counters, reward-term state (the lifetime
            memory) and rng states are carried over, the curriculum is ``cfg``'s own (its
            stage follows from the step count), and the source run's metrics.jsonl rows up
            to the checkpoint's step are copied, so curves continue. ``cfg`` is usually
            the checkpoint's own, changed by the command line
            (:func:`~devlearn.config.resolve.resolve_config` with ``start_from``).
        infant_factory: Infant builder for the envs (tests); default the real infant.
        progress: Show a progress bar.
        force: Start a new run in ``cfg.out_dir`` even if it holds one (its contents are
            deleted once the new run has started); without it such a folder is refused.
        started: Called with the run folder once every check has passed and the envs and
            networks are built, before training (``devlearn run`` prints it there, so a refusal
            or a start-up failure prints only its error).

    Everything that can be checked (config values, the checkpoint's env count, memory, the
    folder) is checked before anything is written; a start that fails anyway (e.g. the envs
    cannot be built) leaves the run folder as it was. The run holds the folder's lock
    (:func:`~devlearn.training.run_folder.locked`) from its start to its end.

    Raises:
        UsageError: Bad input, named; another process training in the folder (``RUN is in use
            by pid N``); :class:`~devlearn.api.errors.RunStopped` when a reward or
            observation guard or a dead env worker stopped training (a checkpoint of the
            last good state is written first).
    """
    # Config (and, when resuming, the checkpoint it continues from).
    checkpoint: dict[str, Any] | None = None
    ckpt_path: str | Path | None = None
    behavior: Behavior | None = None
    if resume is not None:
        ckpt_path, checkpoint = resume_checkpoint(Path(resume))
        cfg = cfg or resolve_run(RunRequest(resume=str(resume)), registry)
    if isinstance(cfg, ResolvedRun):  # the behaviour resolving built, and checked, for it
        cfg, behavior = cfg.cfg, cfg.behavior
    if resume is not None:
        run_dir = Path(resume)
        assert cfg is not None and checkpoint is not None and ckpt_path is not None
        check_resumable(cfg, checkpoint, ckpt_path)
    elif cfg is None:
        raise UsageError("train() needs a config or a run directory to resume")
    else:
        run_dir = Path(cfg.out_dir) if cfg.out_dir else default_run_dir(cfg.behavior_name)
        if start_from is not None:
            opened = Checkpoint.open(start_from, registry, cfg.behavior_name, RESUME_KEYS)
            checkpoint, ckpt_path = opened.state, start_from
            check_resumable(cfg, checkpoint, start_from)
            cfg.start_from = str(start_from)
    rank = int(os.environ.get("RANK", "0"))
    if resume is None and rank == 0 and holds_run(run_dir) and not force:
        if not (run_dir / LATEST).exists() and not periodic_checkpoints(run_dir):
            raise UsageError(
                f"--out {run_dir} holds a run that stopped before its first checkpoint "
                "(nothing to resume); replace it with --force (deletes what the folder holds)"
            )
        raise UsageError(
            f"--out {run_dir} already holds a run; continue it with --resume {run_dir}, "
            "or replace it with --force (deletes what the folder holds)"
        )
    cfg.out_dir = str(run_dir)
    check_out_dir(run_dir)
    check_run_files(run_dir)
    world_size = int(os.environ.get("WORLD_SIZE", "1"))
    device = resolve_device(cfg.device, int(os.environ.get("LOCAL_RANK", "0")), world_size)
    cfg.workers = resolve_workers(cfg.workers, cfg.num_envs)  # config.json records the number
    learned = LearnedRewards.from_config(cfg, registry)  # names checked before the slow set-up
    check_memory(cfg.num_envs, cfg.workers)
    ctx = RunContext(
        cfg, registry, run_dir, rank, world_size, device, learned,
        checkpoint, ckpt_path, start_from, infant_factory, progress, behavior,
    )  # fmt: skip
    # The folder is this process's for the run's life: a second run on it (--resume, --out
    # --force) is refused rather than interleaving its steps or deleting these checkpoints.
    with locked(run_dir, owner=rank == 0) as created:
        with start_up(run_dir, replace=force and resume is None, owner=rank == 0, created=created):
            env, runner = _build(ctx)
        if started is not None and rank == 0:  # built: a start-up error was one line
            started(run_dir)
        try:
            # Learn; the runner saves checkpoints periodically, at the end and on Ctrl-C.
            runner.learn(cfg.total_steps)
        except OSError as exc:
            if exc.errno not in (errno.ENOSPC, errno.EDQUOT):
                raise
            raise UsageError(
                f"disk full: cannot write {exc.filename or run_dir}; free some space, then "
                f"continue with --resume {run_dir}"
            ) from None
        finally:
            env.close()
    return TrainResult(
        run_dir,
        runner.env_steps,
        runner.current_learning_iteration,
        runner.last_row,
        list(runner.health.warnings),
    )


def _build(ctx: RunContext) -> tuple[DevVecEnv, DevRunner]:
    """Start-up after the checks: seed, prepare the behaviour, write config.json, build the
    envs and the runner (restored from ``ctx.checkpoint``, with the learned rewards; from
    another run's when ``ctx.start_from`` names it); return ``(env, runner)``."""
    cfg, run_dir, rank, checkpoint = ctx.cfg, ctx.run_dir, ctx.rank, ctx.checkpoint

    # Seed. The runner sets the torch threads of each rollout and update (ThreadPlan); a
    # fixed torch_threads keeps CPU results bit-for-bit repeatable.
    seed_everything(cfg.seed)
    if cfg.torch_threads > 0:
        torch.set_num_threads(cfg.torch_threads)

    # Behaviour: one-off preparation, then the resolved config is written next to the logs.
    # With several ranks, rank 0 prepares first; the others then reuse what it saved.
    behavior = ctx.behavior or ctx.registry.create(cfg.behavior_name, cfg.behavior)
    if ctx.infant_factory is None:  # before prepare, which may render (hand regard's babbling)
        check_senses_render(behavior.episode().senses, behavior.name)
    run_dir.mkdir(parents=True, exist_ok=True)
    if rank == 0:
        remove_temporaries(run_dir)
    init_distributed(ctx.device)
    if rank == 0:
        behavior.artifacts().prepare(run_dir)
    if ctx.world_size > 1:
        torch.distributed.barrier()
    if rank != 0:
        behavior.artifacts().prepare(run_dir)
    cfg.behavior = behavior.config
    if rank == 0:
        write_config_file(cfg, run_dir / CONFIG_FILE)
        rate = cfg.ppo.run_rate(cfg.total_steps)
        if rate != cfg.ppo.learning_rate:
            print(
                f"devlearn: note: a run of {cfg.total_steps:,} steps takes a step size of "
                f"{rate:.3g} ({cfg.ppo.learning_rate:g} up to {cfg.ppo.full_rate_steps:,} "
                "steps; ppo.full_rate_steps=0 keeps it for any run)",
                file=sys.stderr,
            )

    # Environments (seeded seed + rank * num_envs + index) and the runner.
    # The body at the run's age at its step: a resumed growing run goes on at its schedule's
    # age, a fixed one at its config's (a checkpoint records the body it last trained with).
    steps = int(checkpoint["env_steps"]) if checkpoint else 0
    age = start_age(cfg, steps, behavior.curriculum().stage_index_at(steps))
    if checkpoint is not None and rank == 0 and growth_schedule(cfg) is None:
        trained = checkpoint.get("age_months", age)
        if trained != age:
            print(
                f"devlearn: note: the checkpoint's body was {_body(trained)}; this run goes on "
                f"with {_body(age)} (infant.age_months)",
                file=sys.stderr,
            )
    env = DevVecEnv(
        behavior,
        cfg.num_envs,
        cfg.seed,
        cfg.workers,
        "cpu",
        ctx.infant_factory,
        rank,
        age_months=age,
        settings=EnvSettings.of(cfg.env),  # the envs' one source
    )
    try:
        train_cfg = to_rsl_rl(cfg, behavior, list(env.observation_shapes))
        train_cfg["logger"] = logger_config(cfg)
        runner = DevRunner(
            env,
            train_cfg,
            cfg,
            run_dir,
            behavior.curriculum(),
            headline_metric=behavior.about.headline_metric,
            device=ctx.device,
            progress=ctx.progress,
            learned=ctx.learned,
            run_metrics=behavior.evaluation().run_metrics,
        )
        if checkpoint is not None:
            if ctx.start_from is not None and rank == 0:
                copy_metrics(Path(ctx.start_from).parent, run_dir, int(checkpoint["env_steps"]))
            source = f"checkpoint {ctx.checkpoint_path}"
            _restore(runner, checkpoint, ctx.start_from is None, source)
        if rank > 0:
            # Every rank built its networks from the same seed (rank 0's are broadcast anyway);
            # from here on each rank draws its own action noise, also after a resume, which
            # restores rank 0's generator states everywhere.
            seed_everything(rank_seed(cfg.seed, rank, runner.env_steps))
    except BaseException:
        env.close()
        raise
    return env, runner


def _body(age: float | None) -> str:
    return "the default body" if age is None else f"the body at {age:g} months"


def _restore(runner: DevRunner, checkpoint: dict[str, Any], curriculum: bool, source: str) -> None:
    """``runner.restore`` after checking that the checkpoint's weights fit the networks this
    config builds; a value that still does not load is one line naming the checkpoint."""
    fresh = runner.alg.save()
    for key in ("actor_state_dict", "critic_state_dict"):
        if key in fresh:
            check_fits(fresh[key], checkpoint[key], source, key)
    try:
        runner.restore(checkpoint, curriculum=curriculum)
    except (RuntimeError, ValueError, TypeError, KeyError, IndexError) as exc:
        reason = " ".join(str(exc).split())
        reason = reason if len(reason) <= 200 else reason[:197] + "..."
        raise UsageError(f"{source} cannot be restored: {type(exc).__name__}: {reason}") from None
