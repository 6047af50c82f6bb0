"""DevRunner: our training loop over rsl-rl's parts (its PPO, storage and logger, through their
public API), with a curriculum, metrics.jsonl and atomic checkpoints (held objects:
:class:`~devlearn.training.runner_checkpoints.RunCheckpoints`,
:class:`~devlearn.training.runner_metrics.MetricsLog`)."""

from __future__ import annotations

import contextlib
import io
import math
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import torch
from rsl_rl.algorithms import PPO
from rsl_rl.utils import check_nan, resolve_callable
from rsl_rl.utils.logger import Logger
from tqdm import tqdm

from devlearn.api.behavior import RunMetrics
from devlearn.api.curriculum import Curriculum
from devlearn.api.errors import RunStopped, UsageError
from devlearn.config.growth import growth_schedule
from devlearn.config.run_config import RunConfig
from devlearn.env.guards import GuardError
from devlearn.env.workers import EnvWorkerError
from devlearn.files import write_text_atomically
from devlearn.training.checkpoint import LATEST
from devlearn.training.health import HealthWatch, rollout_health
from devlearn.training.learned_rewards import LearnedRewards
from devlearn.training.process import (
    Ranks,
    StopRequests,
    ThreadPlan,
    init_distributed,
    interrupts_deferred,
    quiet,
    set_threads,
)
from devlearn.training.reward_norm import RewardNormalizer
from devlearn.training.runner_checkpoints import RunCheckpoints
from devlearn.training.runner_metrics import IterationFigures, MetricsLog, purge_tensorboard_from

if TYPE_CHECKING:
    from devlearn.env import DevVecEnv


@dataclass
class Rollout:
    """What one iteration's rollout gathered besides PPO's storage."""

    finished: list[dict[str, Any]]
    """The finished episodes' figures (``reward/<term>``, ``metrics/<name>``, records)."""
    mean_step_reward: float
    """Mean reward per step (raw, before normalisation and learned rewards)."""
    seconds: float
    """Wall time of the rollout (the learned rewards and returns not included)."""
    health: dict[str, float]
    """The learner's figures over the rollout (:func:`~devlearn.training.health.rollout_health`)."""


class DevRunner:
    """Trains one behaviour: collect, update, log, checkpoint, in our own loop.

    It composes rsl-rl's parts through their public API (``PPO.construct_algorithm``, the
    algorithm's ``act`` / ``process_env_step`` / ``compute_returns`` / ``update``, its rollout
    storage and its ``Logger``) instead of subclassing its ``OnPolicyRunner``, whose private
    multi-GPU set-up hard-codes NCCL and cuda (we set up gloo on the CPU ourselves).

    Additions: the curriculum advances from the global env-step counter
    (``iterations * num_steps_per_env * num_envs * world_size``) before each iteration; a tqdm
    bar and ``metrics.jsonl`` (:attr:`metrics`, a
    :class:`~devlearn.training.runner_metrics.MetricsLog`); checkpoints (:attr:`checkpoints`, a
    :class:`~devlearn.training.runner_checkpoints.RunCheckpoints`: model, optimiser,
    iteration, env steps, curriculum, every env's reward-term state, rng states, behaviour
    name, config) written atomically as ``checkpoint_latest.pt`` every ``save_interval // 10``
    iterations, plus ``checkpoint_<step>.pt`` every ``save_interval``, before the first
    iteration of a new curriculum stage (the stage-switch checkpoint another run may start
    from with ``devlearn run --from``), at the end and on Ctrl-C or SIGTERM; the run-wide
    reward memory merged across env workers and ranks at every iteration boundary
    (:meth:`~devlearn.env.DevVecEnv.sync_run_memory`); a body that grows (``infant.growth``:
    the schedule's age given to the envs before each iteration, recorded in checkpoints);
    CPU distributed training over gloo;
    learned rewards (``RunConfig.curiosity``), added to the rollout's rewards and trained
    after each rollout, logged under ``reward/<name>/...`` and saved in checkpoints
    (:mod:`devlearn.training.learned_rewards`). ``current_learning_iteration`` counts
    *completed* iterations, so a resumed run logs each iteration index once.

    ``learn`` makes rsl-rl's calls in the order its own runner makes them (``act``,
    ``env.step``, ``process_env_step``, ``compute_returns``, ``update``, ``logger.log``, with
    rsl-rl's intrinsic-reward (RND) values passed to its logger), but counts environment steps
    rather than iterations (the curriculum and ``total_steps`` are in steps), sets the torch
    threads of each rollout and update
    (:class:`~devlearn.training.process.ThreadPlan`), writes the progress bar and
    ``metrics.jsonl`` and saves devlearn checkpoints instead of rsl-rl's ``model_<it>.pt``.

    Args:
        env: The DevVecEnv.
        train_cfg: From :func:`~devlearn.config.run_config.to_rsl_rl`.
        cfg: The run config (saved in checkpoints; its ``ppo``, ``env`` and thread settings
            are read here, everything rsl-rl reads comes from ``train_cfg``).
        run_dir: Where logs and checkpoints go.
        curriculum: The behaviour's curriculum.
        headline_metric: Evaluator key shown on the progress bar.
        device: Torch device of the networks.
        progress: Show the progress bar (rank 0 only).
        learned: The run's learned rewards (built here, after the networks, so the networks'
            initial parameters do not depend on them); see
            :class:`~devlearn.training.learned_rewards.LearnedRewards`.
        run_metrics: The behaviour's metrics over all finished training episodes
            (:meth:`~devlearn.api.behavior.Behavior.run_metrics`), fed every iteration's episode
            records (all ranks'), logged as ``metrics/<name>`` and saved in checkpoints.
    """

    def __init__(
        self,
        env: DevVecEnv,
        train_cfg: dict,
        cfg: RunConfig,
        run_dir: Path,
        curriculum: Curriculum,
        *,
        headline_metric: str = "",
        device: str = "cpu",
        progress: bool = True,
        learned: LearnedRewards | None = None,
        run_metrics: RunMetrics | None = None,
    ) -> None:
        self.run_cfg = cfg
        self.run_dir = Path(run_dir)
        self.curriculum = curriculum
        self.growth = growth_schedule(cfg)
        """The body's age over the run (``infant.growth``; None: it keeps its age)."""
        if self.growth is not None and self.growth.by_stage:
            if len(self.growth.ages) > len(curriculum.stages):
                raise UsageError(
                    f"infant.growth '{cfg.infant.growth}' names {len(self.growth.ages)} ages, "
                    f"but {cfg.behavior_name}'s curriculum has {len(curriculum.stages)} "
                    f"stage(s): {', '.join(s.name for s in curriculum.stages)}"
                )
        self.show_progress = progress
        self.env_steps = 0
        self.env = env
        self.cfg = train_cfg
        self.device = device
        self.current_learning_iteration = 0
        self._configure_distributed()
        report = io.StringIO()
        with contextlib.redirect_stdout(report):  # rsl-rl prints the networks: networks.txt
            alg_class: type[PPO] = resolve_callable(train_cfg["algorithm"]["class_name"])
            self.alg = alg_class.construct_algorithm(env.get_observations(), env, train_cfg, device)
            self.logger = Logger(
                log_dir=str(self.run_dir),
                cfg=train_cfg,
                env_cfg=cfg,  # the run config, which W&B records
                num_envs=env.num_envs,
                is_distributed=self.is_distributed,
                gpu_world_size=self.gpu_world_size,
                gpu_global_rank=self.gpu_global_rank,
                device=device,
            )
        self.ranks = Ranks(self.gpu_global_rank, self.gpu_world_size)
        self.is_main = self.ranks.is_main
        self.learned = (learned or LearnedRewards()).build(
            env.observation_shapes, env.num_actions, self.device
        )
        self.action_repeat = env.settings.action_repeat  # the envs' own (EnvSettings)
        self.reward_norm = None
        if cfg.ppo.normalize_rewards:
            self.reward_norm = RewardNormalizer(
                env.num_envs, cfg.ppo.gamma, cfg.ppo.reward_clip
            ).to(self.device)
        dist_cfg = train_cfg["actor"]["distribution_cfg"]
        self.health = HealthWatch(
            (dist_cfg.get("min_std", 1e-3), dist_cfg.get("max_std", 0.0)),
            adaptive=cfg.ppo.schedule == "adaptive",
        )
        self.checkpoints = RunCheckpoints(
            self.alg,
            env,
            curriculum,
            self.learned,
            self.reward_norm,
            run_metrics,
            cfg,
            self.run_dir,
            self.ranks,
        )
        self.metrics = MetricsLog(
            self.run_dir, curriculum, self.learned, run_metrics, headline_metric, self.is_main
        )
        if self.is_main:
            write_text_atomically(self.run_dir / "networks.txt", report.getvalue())

    @property
    def last_row(self) -> dict[str, Any]:
        """The last metrics.jsonl row."""
        return self.metrics.last_row

    def restore(self, state: dict[str, Any], curriculum: bool = True) -> None:
        """Continue from a checkpoint (:meth:`RunCheckpoints.restore
        <devlearn.training.runner_checkpoints.RunCheckpoints.restore>`), counters included."""
        self.current_learning_iteration, self.env_steps = self.checkpoints.restore(
            state, curriculum
        )

    # --- distributed ----------------------------------------------------------------------
    def _configure_distributed(self) -> None:
        """Ranks from torchrun's env vars; gloo on the CPU (rsl-rl's own set-up hard-codes NCCL
        and cuda). ``cfg["multi_gpu"]`` is what rsl-rl's PPO reads to all-reduce gradients."""
        self.gpu_world_size = int(os.getenv("WORLD_SIZE", "1"))
        self.is_distributed = self.gpu_world_size > 1
        self.gpu_local_rank = int(os.getenv("LOCAL_RANK", "0"))
        self.gpu_global_rank = int(os.getenv("RANK", "0"))
        if not self.is_distributed:
            self.cfg["multi_gpu"] = None
            return
        self.cfg["multi_gpu"] = {
            "global_rank": self.gpu_global_rank,
            "local_rank": self.gpu_local_rank,
            "world_size": self.gpu_world_size,
        }
        init_distributed(self.device)
        if torch.device(self.device).type == "cuda":
            torch.cuda.set_device(self.gpu_local_rank)

    # --- training loop --------------------------------------------------------------------
    def learn(self, total_steps: int) -> None:
        """Train until ``total_steps`` environment steps (all envs, all ranks) are done."""
        env, alg = self.env, self.alg
        threads = ThreadPlan(
            self.run_cfg.torch_threads, self.run_cfg.update_threads, workers=env.workers
        )
        # physics steps: each decision holds its action for action_repeat of them
        per_iteration = (
            self.cfg["num_steps_per_env"] * env.num_envs * self.gpu_world_size * self.action_repeat
        )
        start_it = self.current_learning_iteration
        total_it = start_it + max(math.ceil((total_steps - self.env_steps) / per_iteration), 0)
        obs = env.get_observations().to(self.device)
        alg.train_mode()
        if self.is_distributed:
            alg.broadcast_parameters()
            self.learned.broadcast()
        with quiet():
            self.logger.init_logging_writer()
        if start_it > 0:
            purge_tensorboard_from(self.logger.writer, start_it)
        self.curriculum.update(self.env_steps)
        env.set_stage(self.curriculum.stage.options)
        self._grow(total_steps)
        bar = tqdm(
            total=total_steps,
            initial=self.env_steps,
            unit="step",
            unit_scale=True,
            disable=not (self.is_main and self.show_progress),
            dynamic_ncols=True,
        )
        good = None  # the state at the last iteration boundary (what a fault checkpoint saves)
        try:
            good = self.checkpoints.snapshot(self.current_learning_iteration, self.env_steps)
            while self.env_steps < total_steps:
                if self.curriculum.update(self.env_steps):
                    env.set_stage(self.curriculum.stage.options)
                self._grow(total_steps)
                if alg.actor.distribution is not None:  # network.final_std's ceiling, if any
                    alg.actor.distribution.set_progress(self.env_steps / total_steps)
                if self.run_cfg.ppo.schedule == "linear":  # ppo.schedule=linear: lr -> 0
                    alg.set_learning_rate(self.run_cfg.ppo.linear_rate(self.env_steps, total_steps))
                collect_threads, learn_threads = threads.next_iteration()

                # Collect: a rollout with the workers stepping while the policy acts.
                set_threads(collect_threads)
                obs, rollout = self._collect(obs)

                # Update: PPO (the workers sleep).
                start = time.time()
                set_threads(learn_threads)
                losses = alg.update()
                learn_time = time.time() - start
                threads.record(learn_time)

                # Log: the boundary, its snapshot and its metrics row: all or none on an
                # interrupt.
                it = self.current_learning_iteration
                with interrupts_deferred():
                    self.current_learning_iteration += 1
                    self.env_steps += per_iteration
                    # one agent's lifetime memory: merge the workers' (and ranks') copies
                    env.sync_run_memory(self.ranks.all_gather if self.is_distributed else None)
                    self.metrics.add_episode_records(
                        rollout.finished, self.ranks.all_gather if self.is_distributed else None
                    )
                    good = self.checkpoints.snapshot(
                        self.current_learning_iteration, self.env_steps
                    )
                    times = {
                        "collect_s": rollout.seconds,
                        "update_s": learn_time,
                        "update_threads": learn_threads,
                    }
                    self._log(it, start_it, total_it, rollout, losses, times, per_iteration, bar)

                # Checkpoint: periodic and stage-switch files, and the latest often.
                self._save_on_schedule(good)
        except KeyboardInterrupt:
            # The rollout (and update) under way is thrown away: the checkpoint holds the last
            # iteration boundary, "first ever" memories and rng states included.
            if good is None:
                good = self.checkpoints.snapshot(self.current_learning_iteration, self.env_steps)
            self.checkpoints.save(good, periodic=False, gather=False)
            if self.is_main:
                print(
                    f"\ninterrupted: checkpoint saved in {self.run_dir / LATEST}", file=sys.stderr
                )
            raise
        except (GuardError, EnvWorkerError) as exc:
            saved = self.checkpoints.save_after_fault(good)
            if isinstance(exc, GuardError) or exc.died:
                rank = f" on rank {self.gpu_global_rank}" if self.is_distributed else ""
                # counted from 1, of the run's total: the iteration under way, after the
                # completed ones the checkpoint holds
                under_way = self.current_learning_iteration + 1
                raise RunStopped(
                    f"{exc}{rank}, during iteration {under_way} of {total_it}; {saved}"
                ) from None
            print(f"devlearn: {saved}", file=sys.stderr)
            raise
        finally:
            bar.close()
        final = self.checkpoints.snapshot(self.current_learning_iteration, self.env_steps)
        self.checkpoints.save(final, periodic=True)
        with quiet():
            self.logger.stop_logging_writer()
            if self.logger.writer is not None:
                self.logger.writer.close()

    def _grow(self, total_steps: int) -> None:
        """Give the envs the growth schedule's age at this step; they rebuild their physics
        only when it changed (once per env, carrying their episodes on)."""
        if self.growth is not None:
            age = self.growth.age_at(self.env_steps, total_steps, self.curriculum.index)
            self.env.set_age(age)

    def _collect(self, obs: Any) -> tuple[Any, Rollout]:
        """One rollout of ``num_steps_per_env`` decisions into PPO's storage, the learned
        rewards added and the returns computed; return the last observations and the rest."""
        env, alg = self.env, self.alg
        rnd = bool(self.cfg["algorithm"].get("rnd_cfg"))
        start = time.time()
        finished: list[dict[str, Any]] = []
        step_rewards = 0.0
        with torch.inference_mode():
            for _ in range(self.cfg["num_steps_per_env"]):
                StopRequests.check()  # Ctrl-C / SIGTERM, here between decisions
                actions = alg.act(obs)
                obs, rewards, dones, extras = env.step(actions.to(env.device))
                if self.cfg.get("check_for_nan", True):
                    check_nan(obs, rewards, dones)
                obs, rewards = obs.to(self.device), rewards.to(self.device)
                dones = dones.to(self.device)
                ppo_rewards = rewards
                if self.reward_norm is not None:  # PPO sees the scaled rewards
                    ppo_rewards = self.reward_norm(rewards, dones)
                alg.process_env_step(obs, ppo_rewards, dones, extras)
                intrinsic = alg.intrinsic_rewards if rnd else None
                self.logger.process_env_step(rewards, dones, extras, intrinsic)
                finished += extras["episode_infos"]
                step_rewards += float(rewards.mean())
            seconds = time.time() - start
            self.learned.apply(alg.storage, obs, self.env_steps)  # adds to the rewards
            alg.compute_returns(obs)
            health = rollout_health(alg.storage)
        mean_step = step_rewards / self.cfg["num_steps_per_env"]
        return obs, Rollout(finished, mean_step, seconds, health)

    def _log(
        self,
        it: int,
        start_it: int,
        total_it: int,
        rollout: Rollout,
        losses: dict[str, float],
        times: dict[str, float],
        per_iteration: int,
        bar: tqdm,
    ) -> None:
        """rsl-rl's log (TensorBoard, W&B), then metrics.jsonl and the progress bar, then the
        learner-health warnings."""
        alg = self.alg
        rnd = bool(self.cfg["algorithm"].get("rnd_cfg"))
        with quiet():
            self.logger.log(
                it=it,
                start_it=start_it,
                total_it=total_it,
                collect_time=times["collect_s"],
                learn_time=times["update_s"],
                loss_dict=losses,
                learning_rate=alg.learning_rate,
                action_std=alg.get_policy().output_std,
                rnd_weight=alg.rnd.weight if rnd else None,
            )
        rate = per_iteration / max(times["collect_s"] + times["update_s"], 1e-9)
        health = rollout.health
        health["learning_rate"] = alg.learning_rate
        if self.reward_norm is not None:
            health["health/reward_scale"] = self.reward_norm.std
        figures = IterationFigures(
            iteration=it,
            env_steps=self.env_steps,
            finished=rollout.finished,
            mean_step_reward=rollout.mean_step_reward,
            losses=losses,
            steps_per_s=rate,
            times=times,
            health=health,
            age_months=self.env.age_months,
        )
        row = self.metrics.record(figures, bar, self.logger.writer)
        for warning in self.health.check(row):
            if self.is_main:
                tqdm.write(f"devlearn: {warning}", file=sys.stderr)

    def _save_on_schedule(self, good: dict[str, Any]) -> None:
        """``checkpoint_<step>.pt`` every ``save_interval`` iterations and before the first
        iteration of a new curriculum stage; the latest every ``save_interval // 10``."""
        interval = self.cfg["save_interval"]
        done = self.current_learning_iteration
        switch = self.curriculum.stage_index_at(self.env_steps) != self.curriculum.index
        if done % interval == 0 or switch:
            self.checkpoints.save(good, periodic=True)
        elif done % max(1, interval // 10) == 0:
            self.checkpoints.save(good, periodic=False)  # little lost on a kill
