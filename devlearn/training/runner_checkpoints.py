"""The runner's checkpoints: the state at an iteration boundary, written atomically, restored on
resume (:class:`RunCheckpoints`, held by :class:`~devlearn.training.runner.DevRunner`)."""

from __future__ import annotations

import copy
import random
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import torch

from devlearn.config.run_config import to_dict
from devlearn.training.checkpoint import FORMAT, LATEST, link_atomic, save_atomic
from devlearn.training.process import Ranks
from devlearn.training.run_folder import forget_metrics_after

if TYPE_CHECKING:
    from devlearn.api.behavior import RunMetrics
    from devlearn.api.curriculum import Curriculum
    from devlearn.config.run_config import RunConfig
    from devlearn.env import DevVecEnv
    from devlearn.training.learned_rewards import LearnedRewards
    from devlearn.training.reward_norm import RewardNormalizer


class RunCheckpoints:
    """Snapshot, save and restore everything a run needs to continue.

    A checkpoint holds the model and optimiser (``alg.save()``), iteration, env steps,
    curriculum, the body's age (``age_months``, None: the default body), every env's
    reward-term state, the learned rewards, the reward normaliser,
    the run metrics (e.g. self-touch's training-score window), rng states, behaviour name and
    config (``docs/checkpoints.md``).

    Args:
        alg: The PPO algorithm (``save()``, ``load()``, ``learning_rate``, ``set_learning_rate()``).
        env: The DevVecEnv (``state_dict()``, ``load_state_dict()``, ``sync_run_memory()``).
        curriculum: The behaviour's curriculum.
        learned: The run's learned rewards.
        reward_norm: The reward normaliser (None: rewards are not normalised).
        run_metrics: The behaviour's run metrics (None: it has none).
        cfg: The run config (saved in every checkpoint).
        run_dir: Where checkpoints go.
        ranks: This process's rank (only rank 0 writes; env states are gathered from all).
    """

    def __init__(
        self,
        alg: Any,
        env: DevVecEnv,
        curriculum: Curriculum,
        learned: LearnedRewards,
        reward_norm: RewardNormalizer | None,
        run_metrics: RunMetrics | None,
        cfg: RunConfig,
        run_dir: Path,
        ranks: Ranks,
    ) -> None:
        self.alg = alg
        self.env = env
        self.curriculum = curriculum
        self.learned = learned
        self.reward_norm = reward_norm
        self.run_metrics = run_metrics
        self.cfg = cfg
        self.run_dir = Path(run_dir)
        self.ranks = ranks

    def snapshot(self, iteration: int, env_steps: int) -> dict[str, Any]:
        """A copy of this rank's state after ``iteration`` completed iterations and
        ``env_steps`` steps, kept while the next iteration runs so that an interrupt or fault
        mid-rollout saves that boundary rather than half an iteration."""
        state = copy.deepcopy(self.alg.save())
        state.update(
            iteration=iteration,
            env_steps=env_steps,
            curriculum=copy.deepcopy(self.curriculum.state_dict()),
            env=copy.deepcopy(self.env.state_dict()),
            learning_rate=self.alg.learning_rate,
            age_months=self.env.age_months,
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

    def checkpoint_state(self, snapshot: dict[str, Any], gather: bool = True) -> dict[str, Any]:
        """The checkpoint of a :meth:`snapshot`: every rank's env state (a collective when
        distributed and ``gather``), the format, behaviour name and config added."""
        state = dict(snapshot)
        env_state = state.pop("env")
        ranks = self.ranks.all_gather(env_state) if gather else [env_state]
        state.update(
            format=FORMAT,
            behavior=self.cfg.behavior_name,
            config=to_dict(self.cfg),
            env={"ranks": ranks},
        )
        return state

    def save(self, snapshot: dict[str, Any], periodic: bool, gather: bool = True) -> Path | None:
        """Write ``checkpoint_latest.pt`` (and ``checkpoint_<step>.pt`` when ``periodic``) from
        a :meth:`snapshot`; return the latest file's path (None on ranks other than 0)."""
        state = self.checkpoint_state(snapshot, gather)
        if not self.ranks.is_main:
            return None
        latest = self.run_dir / LATEST
        if periodic:
            path = self.run_dir / f"checkpoint_{state['env_steps']}.pt"
            save_atomic(state, path)
            link_atomic(path, latest)
        else:
            save_atomic(state, latest)
        return latest

    def save_after_fault(self, good: dict[str, Any] | None) -> str:
        """Write the last good :meth:`snapshot` after a fault (gathering nothing: the other
        ranks may be gone); return a sentence saying where (or why not)."""
        if good is None:
            return "no checkpoint could be written (the fault came before the first iteration)"
        try:
            path = self.save(good, periodic=False, gather=False)
        except Exception as exc:  # e.g. the disk is full too
            return f"no checkpoint could be written ({exc})"
        return (
            f"the last good state (step {good['env_steps']}) is saved in "
            f"{path or self.run_dir / LATEST}; continue with --resume {self.run_dir}"
        )

    def restore(self, state: dict[str, Any], curriculum: bool = True) -> tuple[int, int]:
        """Resume from a checkpoint: networks, optimiser, curriculum, learned rewards, envs,
        rngs; return its ``(iteration, env_steps)``. ``curriculum=False`` (``devlearn run
        --from``) leaves this run's own curriculum, whose stage then follows from the step
        count alone."""
        self.alg.load(state, None, strict=True)  # also takes the adaptive lr from the optimiser
        if self.cfg.ppo.schedule == "fixed":  # a fixed schedule means the configured lr
            self.alg.set_learning_rate(self.cfg.ppo.run_rate(self.cfg.total_steps))
        iteration, env_steps = int(state["iteration"]), int(state["env_steps"])
        if curriculum:
            self.curriculum.load_state_dict(state["curriculum"])
        else:
            self.curriculum.update(env_steps)
        self.learned.load_state_dict(state.get("learned", {}))
        if self.reward_norm is not None and state.get("reward_norm"):
            self.reward_norm.load_state_dict(state["reward_norm"])
        if self.run_metrics is not None and state.get("run_metrics"):
            self.run_metrics.load_state_dict(state["run_metrics"])
        ranks = state["env"]["ranks"]
        if self.ranks.rank < len(ranks):
            self.env.load_state_dict(ranks[self.ranks.rank])
        # every env's saved state holds the run memory it had: merge across workers (and
        # ranks), e.g. after a per-env run is continued with shared memory
        self.env.sync_run_memory(self.ranks.all_gather if self.ranks.is_distributed else None)
        if self.ranks.is_main:
            forget_metrics_after(self.run_dir / "metrics.jsonl", env_steps)
        torch.set_rng_state(state["rng"]["torch"])
        np.random.set_state(state["rng"]["numpy"])
        random.setstate(state["rng"]["random"])
        return iteration, env_steps
