"""DevVecEnv: a batch of BehaviorEnvs behind rsl-rl's VecEnv interface."""

from __future__ import annotations

import os
import weakref
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
import torch
from rsl_rl.env import VecEnv
from tensordict import TensorDict

from devlearn.env.behavior_env import (
    EPISODE_RECORD,
    InfantFactory,
    batched_reward_terms,
    env_settings,
    load_run_memories,
    merge_run_memories,
    run_memories,
)
from devlearn.env.buffers import EnvBuffers, env_spec, write_obs
from devlearn.env.rendering import check_senses_render
from devlearn.env.workers import EpisodeInfos, WorkerPool, make_envs, step_envs

if TYPE_CHECKING:
    from devlearn.api.behavior import Behavior
    from devlearn.env.settings import EnvSettings


class DevVecEnv(VecEnv):
    """``num_envs`` BehaviorEnvs of one behaviour, stepped together (rsl-rl's VecEnv).

    Env ``i`` on distributed rank ``r`` is seeded ``seed + r * num_envs + i``. With
    ``workers=0`` the envs run one after another in this process; with ``workers >= 1`` they
    are split over that many worker processes that write observations, rewards and flags
    straight into shared memory (only short commands and finished-episode summaries travel
    through pipes). A failing worker's traceback is re-raised here as
    :class:`~devlearn.env.workers.EnvWorkerError`; workers exit when this process dies.

    Args:
        behavior: The behaviour; every env gets its own copy.
        num_envs: Number of sub-environments on this rank.
        seed: Base seed.
        workers: Worker processes (0: in process).
        device: Torch device of the returned tensors.
        infant_factory: ``factory(scene, senses=...) -> Infant`` (default: the real infant);
            must be picklable when ``workers >= 1``.
        rank: Distributed rank for seeding (default: ``$RANK`` or 0).
        action_repeat: Shorthand for ``settings=EnvSettings(action_repeat)``; not with
            ``settings``.
        age_months: The body's age (months; None: the default body); :meth:`set_age`
            changes it.
        settings: The run's settled env settings (default ``EnvSettings()``), handed down to
            every env: its ``action_repeat`` physics steps per ``step`` call, one action held
            over them (see :func:`~devlearn.env.behavior_env.step_batch`), rewards their sum.
    """

    def __init__(
        self,
        behavior: Behavior,
        num_envs: int,
        seed: int,
        workers: int = 0,
        device: str = "cpu",
        infant_factory: InfantFactory | None = None,
        rank: int | None = None,
        action_repeat: int | None = None,
        age_months: float | None = None,
        settings: EnvSettings | None = None,
    ) -> None:
        if num_envs < 1:
            raise ValueError(f"num_envs must be at least 1, got {num_envs}")
        if infant_factory is None:  # the real infant, rendered in worker processes too
            check_senses_render(behavior.episode().senses, behavior.name)
        rank = int(os.environ.get("RANK", "0")) if rank is None else rank
        seeds = [seed + rank * num_envs + i for i in range(num_envs)]
        self.settings = env_settings(settings, action_repeat)
        """The run's settled env settings, as every env has them."""
        self.behavior_name = behavior.name
        self._pool: WorkerPool | None = None
        self._envs: list = []
        if workers > 0:
            self._pool = WorkerPool(
                behavior, seeds, workers, infant_factory, self.settings, age_months=age_months
            )
            spec = self._pool.spec
            self._merge_terms = batched_reward_terms(behavior)  # merge rules of the run memory
        else:
            self._envs = make_envs(
                behavior, seeds, infant_factory, settings=self.settings, age_months=age_months
            )
            first = [env.reset() for env in self._envs]
            spec = env_spec(self._envs[0], first[0])
            self._merge_terms = self._envs[0].terms
        self._has_run_memory = any(t.run_memory() for t in self._merge_terms)
        self._buffers = EnvBuffers(spec, num_envs, shared=self._pool is not None)
        self._finalizer = weakref.finalize(self, _shutdown, self._pool, self._envs, self._buffers)
        if self._pool is not None:
            self._pool.call("attach", [self._buffers.handle()] * len(self._pool.conns))
        else:
            for i, obs in enumerate(first):
                write_obs(self._buffers.arrays, i, obs)

        self.age_months = age_months
        """The body's age in every env (months; None: the default body)."""
        self.num_envs = num_envs
        self.num_actions = int(spec["action_dim"])
        self.max_episode_length = int(spec["episode_steps"])
        self.step_dt = float(spec["step_dt"])
        self.observation_shapes = {k: shape for k, (shape, _) in spec["obs"].items()}
        self.term_names: list[str] = list(spec["terms"])
        """The behaviour's reward terms, in the order of ``arrays["term_rewards"]``'s columns."""
        self.device = device
        self.episode_length_buf = torch.zeros(num_envs, dtype=torch.long, device=device)
        self.cfg: Any = {"behavior": behavior.name, "num_envs": num_envs, "seed": seed}

    @property
    def workers(self) -> int:
        """Worker processes stepping the envs (0: they step in this process)."""
        return 0 if self._pool is None else len(self._pool.conns)

    @property
    def unwrapped(self) -> DevVecEnv:
        """This env (rsl-rl's RND extension reads ``env.unwrapped.step_dt``)."""
        return self

    def get_observations(self) -> TensorDict:
        """Return the current observations: one group per observation name, (N, *shape)."""
        arrays = self._buffers.arrays
        groups = {
            name: torch.from_numpy(arrays[f"obs/{name}"].copy()).to(self.device)
            for name in self.observation_shapes
        }
        return TensorDict(groups, batch_size=[self.num_envs], device=self.device)

    def step(self, actions: torch.Tensor) -> tuple[TensorDict, torch.Tensor, torch.Tensor, dict]:
        """Step every env (finished ones reset themselves).

        Args:
            actions: (num_envs, num_actions), clipped to [-1, 1] by each env.
        Returns:
            ``(obs, rewards (N,), dones (N,), extras)``; ``extras["time_outs"]`` (N,) marks
            time-limit ends, ``extras["log"]`` holds the mean ``reward/*`` and ``metrics/*`` over
            the episodes that ended this step (empty if none) and ``extras["episode_infos"]``
            the list of those episodes' summaries.
        """
        infos = self.step_arrays(actions.detach().to("cpu", torch.float32).numpy())
        arrays = self._buffers.arrays
        rewards = torch.from_numpy(arrays["rewards"].copy()).to(self.device)
        dones = torch.from_numpy(arrays["dones"].copy()).to(self.device)
        time_outs = torch.from_numpy(arrays["time_outs"].copy()).to(self.device)
        self.episode_length_buf += 1
        self.episode_length_buf[dones] = 0
        episodes = [info for _, info in infos]
        extras = {"time_outs": time_outs, "log": mean_episode_info(episodes)}
        extras["episode_infos"] = episodes
        return self.get_observations(), rewards, dones.to(torch.long), extras

    @property
    def arrays(self) -> dict[str, np.ndarray]:
        """The batch's arrays (:class:`~devlearn.env.buffers.EnvBuffers`: ``obs/<name>``,
        ``rewards``, ``dones``, ``time_outs``, ``term_rewards``, ``final/<name>``...), which
        every step overwrites: copy what you keep."""
        return self._buffers.arrays

    def step_arrays(self, actions: np.ndarray) -> EpisodeInfos:
        """:meth:`step` without torch: step every env with ``actions`` (num_envs,
        num_actions); the results are in :attr:`arrays` until the next step.

        Returns:
            ``(env index, episode_info)`` of every episode that ended this step.
        """
        self._buffers.arrays["actions"][:] = actions
        if self._pool is None:
            return step_envs(self._envs, 0, self._buffers.arrays)
        return [item for reply in self._pool.call("step") for item in reply]

    def set_stage(self, options: dict[str, Any]) -> None:
        """Send a curriculum stage's options to every env."""
        if self._pool is None:
            for env in self._envs:
                env.set_stage(options)
        else:
            self._pool.call("set_stage", [options] * len(self._pool.conns))

    def set_age(self, age_months: float | None) -> None:
        """Rebuild every env's physics at ``age_months`` (each worker rebuilds its envs once),
        carrying on their episodes (:meth:`~devlearn.env.behavior_env.BehaviorEnv.set_age`)."""
        if age_months == self.age_months:
            return
        if self._pool is None:
            for env in self._envs:
                env.set_age(age_months)
        else:
            self._pool.call("set_age", [age_months] * len(self._pool.conns))
        self.age_months = age_months

    def sync_run_memory(self, gather: Callable[[Any], list] | None = None) -> None:
        """Make every worker's run-wide reward memory the merge of all of them.

        The runner calls this at every PPO iteration boundary (before it snapshots the state
        for checkpoints): each worker's batched terms report their
        :meth:`~devlearn.api.rewards.BatchedIntrinsicReward.run_memory`, the copies are merged in
        worker order (``merge_run_memory``) and sent back. With ``gather`` (the runner's
        all-gather over torchrun ranks: this rank's merged memory -> every rank's, in rank
        order) the ranks' memories are merged too, so every rank holds the same. Nothing is
        sent when no term keeps a run memory, or with one in-process batch and no ``gather``.
        """
        if not self._has_run_memory or (self._pool is None and gather is None):
            return
        if self._pool is None:
            copies = [run_memories(self._envs)]
        else:
            copies = self._pool.call("memory")
        merged = merge_run_memories(self._merge_terms, copies)
        if gather is not None:
            merged = merge_run_memories(self._merge_terms, gather(merged))
        if self._pool is None:
            load_run_memories(self._envs, merged)
        else:
            self._pool.call("load_memory", [merged] * len(self._pool.conns))

    def state_dict(self) -> dict[str, Any]:
        """Return every env's state (reward terms, rng, stage), in env order."""
        if self._pool is None:
            states = [env.state_dict() for env in self._envs]
        else:
            states = [s for reply in self._pool.call("state") for s in reply]
        return {"envs": states}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore :meth:`state_dict`'s output and start fresh episodes in every env."""
        states = state["envs"]
        if len(states) != self.num_envs:
            raise ValueError(f"state holds {len(states)} envs, this batch has {self.num_envs}")
        if self._pool is None:
            for i, (env, env_state) in enumerate(zip(self._envs, states)):
                env.load_state_dict(env_state)
                write_obs(self._buffers.arrays, i, env.reset())
        else:
            self._pool.call("load", self._pool.split(states))
        self.episode_length_buf.zero_()

    def close(self) -> None:
        """Stop workers, close envs and free shared memory (safe to call twice)."""
        self._finalizer()


def mean_episode_info(episodes: list[dict[str, float]]) -> dict[str, float]:
    """Mean of every key over the given episode summaries (keys missing from some are skipped;
    the :data:`~devlearn.env.behavior_env.EPISODE_RECORD` is no number and is left out)."""
    keys = dict.fromkeys(k for ep in episodes for k in ep if k != EPISODE_RECORD)
    return {k: float(np.mean([ep[k] for ep in episodes if k in ep])) for k in keys}


def _shutdown(pool: WorkerPool | None, envs: list, buffers: EnvBuffers) -> None:
    if pool is not None:
        pool.close()
    for env in envs:
        env.close()
    buffers.close()
