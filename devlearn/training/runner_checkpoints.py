"""DevRunner's checkpoints: the state at an iteration boundary, written atomically, restored
on resume (a mixin of :class:`~devlearn.training.runner.DevRunner`)."""

from __future__ import annotations

import copy
import random
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import torch
import torch.distributed as dist

from devlearn.config.run_config import to_dict
from devlearn.training.checkpoint import (
    FORMAT,
    LATEST,
    link_atomic,
    save_atomic,
)
from devlearn.training.run_folder import forget_metrics_after

if TYPE_CHECKING:
    from devlearn.api.behavior import RunMetrics
    from devlearn.api.curriculum import Curriculum
    from devlearn.config.run_config import RunConfig
    from devlearn.env import DevVecEnv
    from devlearn.training.learned_rewards import LearnedRewards
    from devlearn.training.reward_norm import RewardNormalizer


class RunnerCheckpoints:
    """Snapshot, save and restore for :class:`~devlearn.training.runner.DevRunner`.

    Uses the runner's ``alg``, ``env``, ``curriculum``, ``learned``, ``run_cfg``, ``run_dir``,
    counters (``current_learning_iteration``, ``env_steps``), rank attributes and
    ``_all_ranks``. A checkpoint holds the model, optimiser, iteration, env steps,
    curriculum, every env's reward-term state, the learned rewards, the run metrics
    (e.g. self-touch's training-score window), rng states, behaviour name and config
    (``docs/checkpoints.md``).
    """

    # What the host runner provides (DevRunner sets them; rsl-rl's OnPolicyRunner: alg and
    # the rank attributes), declared for the type checker: annotations only, no values.
    alg: Any  # UniqueParamPPO
    env: DevVecEnv
    curriculum: Curriculum
    learned: LearnedRewards
    reward_norm: RewardNormalizer | None
    run_metrics: RunMetrics | None
    run_cfg: RunConfig
    run_dir: Path
    is_main: bool
    is_distributed: bool
    gpu_global_rank: int
    gpu_world_size: int
    _all_ranks: Callable[[Any], list]

    def _snapshot(self) -> dict[str, Any]:
        """A copy of the state at an iteration boundary (the :meth:`checkpoint_state` of this
        rank), kept while the next iteration runs so that an interrupt or fault mid-rollout
        saves that boundary rather than half an iteration."""
        state = copy.deepcopy(self.alg.save())
        state.update(
            iteration=self.current_learning_iteration,
            env_steps=self.env_steps,
            curriculum=copy.deepcopy(self.curriculum.state_dict()),
            env=copy.deepcopy(self.env.state_dict()),
            learning_rate=self.alg.learning_rate,
            learned=copy.deepcopy(self.learned.state_dict()),  # live tensors otherwise
            reward_norm=(
                copy.deepcopy(self.reward_norm.state_dict()) if self.reward_norm is not None else {}
            ),
            run_metrics=(
                copy.deepcopy(self.run_metrics.state_dict()) if self.run_metrics is not None else {}
            ),
            rng={
                "torch": torch.get_rng_state(),
                "numpy": np.random.get_state(),
                "random": random.getstate(),
            },
        )
        return state

    def checkpoint_state(
        self, gather: bool = True, good: dict[str, Any] | None = None
    ) -> dict[str, Any]:
        """Everything needed to resume (collective when distributed and ``gather``): the live
        state, or the boundary snapshot ``good`` taken by :meth:`_snapshot`."""
        state = dict(good) if good is not None else self._snapshot()
        env_state = state.pop("env")
        ranks = [env_state]
        if self.is_distributed and gather:
            ranks = [None] * self.gpu_world_size
            dist.all_gather_object(ranks, env_state)
        state.update(
            format=FORMAT,
            behavior=self.run_cfg.behavior_name,
            config=to_dict(self.run_cfg),
            env={"ranks": ranks},
        )
        return state

    def _fault_checkpoint(self, good: dict[str, Any] | None) -> str:
        """Write the last good state after a fault; return a sentence saying where (or why not)."""
        if good is None:
            return "no checkpoint could be written (the fault came before the first iteration)"
        try:
            path = self.save_checkpoints(periodic=False, gather=False, good=good)
        except Exception as exc:  # e.g. the disk is full too
            return f"no checkpoint could be written ({exc})"
        return (
            f"the last good state (step {good['env_steps']}) is saved in "
            f"{path or self.run_dir / LATEST}; continue with --resume {self.run_dir}"
        )

    def save_checkpoints(
        self, periodic: bool, gather: bool = True, good: dict[str, Any] | None = None
    ) -> Path | None:
        """Write ``checkpoint_latest.pt`` (and ``checkpoint_<step>.pt`` when ``periodic``)
        from the live state or the boundary snapshot ``good``."""
        state = self.checkpoint_state(gather, good)
        if not self.is_main:
            return None
        latest = self.run_dir / LATEST
        if periodic:
            path = self.run_dir / f"checkpoint_{self.env_steps}.pt"
            save_atomic(state, path)
            link_atomic(path, latest)
        else:
            save_atomic(state, latest)
        return latest

    def restore(self, state: dict[str, Any], curriculum: bool = True) -> None:
        """Resume from a checkpoint: networks, optimiser, counters, curriculum, learned rewards,
        envs, rngs. ``curriculum=False`` (``devlearn run --from``) leaves this run's own
        curriculum, whose stage then follows from the step count alone."""
        self.alg.load(state, None, strict=True)  # also takes the adaptive lr from the optimiser
        if self.run_cfg.ppo.schedule == "fixed":  # a fixed schedule means the configured lr
            self.alg.learning_rate = self.run_cfg.ppo.learning_rate
            for group in self.alg.optimizer.param_groups:
                group["lr"] = self.alg.learning_rate
        self.current_learning_iteration = int(state["iteration"])
        self.env_steps = int(state["env_steps"])
        if curriculum:
            self.curriculum.load_state_dict(state["curriculum"])
        else:
            self.curriculum.update(self.env_steps)
        self.learned.load_state_dict(state.get("learned", {}))
        if self.reward_norm is not None and state.get("reward_norm"):
            self.reward_norm.load_state_dict(state["reward_norm"])
        if self.run_metrics is not None and state.get("run_metrics"):
            self.run_metrics.load_state_dict(state["run_metrics"])
        ranks = state["env"]["ranks"]
        if self.gpu_global_rank < len(ranks):
            self.env.load_state_dict(ranks[self.gpu_global_rank])
        # every env's saved state holds the run memory it had: merge across workers (and
        # ranks), e.g. after a per-env run is continued with shared memory
        self.env.sync_run_memory(self._all_ranks if self.is_distributed else None)
        if self.is_main:
            forget_metrics_after(self.run_dir / "metrics.jsonl", self.env_steps)
        torch.set_rng_state(state["rng"]["torch"])
        np.random.set_state(state["rng"]["numpy"])
        random.setstate(state["rng"]["random"])
