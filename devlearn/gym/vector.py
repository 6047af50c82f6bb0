"""DevlearnVectorEnv: a behaviour's batch of environments, over devlearn's own worker pool, as a
``gymnasium.vector.VectorEnv``."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from devlearn.env.settings import EnvSettings
from devlearn.env.vec_env import DevVecEnv
from devlearn.gym.run_setup import (
    CurriculumClock,
    Overrides,
    RunSetup,
    action_space,
    episode_info,
    observation_space,
    require_open,
    step_info,
)

if TYPE_CHECKING:
    from devlearn.env.behavior_env import InfantFactory
    from devlearn.plugins import PluginRegistry


class DevlearnVectorEnv(VectorEnv):
    """``num_envs`` environments of a devlearn behaviour stepped together, in this process or
    in ``workers`` processes with shared memory (:class:`~devlearn.env.DevVecEnv`, the
    environments ``devlearn run`` trains on), as a Gymnasium vector env.

    Made by :func:`devlearn.gym.make_vec` or ``gymnasium.make_vec(id, num_envs, workers=...)``.
    Everything :class:`~devlearn.gym.env.DevlearnEnv` says holds per env; env ``i`` is seeded
    ``seed + i`` as in a run, and ``reset(seed=S)`` reseeds it ``S + i``.

    Autoreset is Gymnasium's ``SAME_STEP`` (``metadata["autoreset_mode"]``), as devlearn's envs
    reset: the step that ends an env's episode returns the next episode's first observation in
    its row, and ``info["final_obs"][i]`` (the last observation, a dict) and
    ``info["final_info"]`` (that env's step info with ``episode/reward/<term>`` and
    ``episode/metrics/<name>``) under the mask ``info["_final_obs"]``. Every step's ``info``
    holds ``reward/<term>`` (num_envs,) and ``stage`` (num_envs,) with their masks.

    Every ``ppo.num_steps_per_env`` steps (a run's iteration) the workers' run-wide reward
    memory is merged and the curriculum advanced to the physics steps taken, as in a run
    (:class:`~devlearn.gym.run_setup.CurriculumClock`). :meth:`close` stops the workers.

    Args:
        behavior: The behaviour's registered name.
        num_envs: Environments (the config's ``num_envs``).
        workers: Worker processes (0: in this process; -1: one per core, as ``devlearn run``).
        overrides: Config values, as ``devlearn run --set`` takes them.
        preset: A preset of the behaviour.
        render_mode: Only None (render a single env: ``gymnasium.make(id,
            render_mode="rgb_array")``).
        registry: Plugin registry (default: the installed plugins).
        infant_factory: Infant builder (tests); must pickle when ``workers >= 1``.
    """

    metadata: dict[str, Any] = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}

    def __init__(
        self,
        behavior: str,
        num_envs: int = 1,
        workers: int = 0,
        overrides: Overrides = None,
        preset: str = "",
        render_mode: str | None = None,
        *,
        registry: PluginRegistry | None = None,
        infant_factory: InfantFactory | None = None,
    ) -> None:
        from devlearn.api.errors import UsageError
        from devlearn.training.process import resolve_workers

        if render_mode is not None:
            raise UsageError(
                "the vector env does not render; render a single env: "
                "gymnasium.make(id, render_mode='rgb_array')"
            )
        top = {"num_envs": num_envs, "workers": workers}
        self.setup = RunSetup(behavior, overrides, preset, top, registry)
        cfg = self.setup.config
        self.clock = CurriculumClock(self.setup.behavior.curriculum(), cfg, cfg.num_envs)
        try:
            self.envs = DevVecEnv(
                self.setup.behavior,
                cfg.num_envs,
                cfg.seed,
                resolve_workers(cfg.workers, cfg.num_envs),
                infant_factory=infant_factory,
                rank=0,
                age_months=self.clock.age_months,
                settings=EnvSettings.of(cfg.env),
            )
        except BaseException:
            self.setup.close()
            raise
        self.num_envs = cfg.num_envs
        self.seed_base = cfg.seed
        self.envs.set_stage(self.clock.stage.options)
        arrays = self.envs.arrays
        self.names = list(self.envs.observation_shapes)
        self.term_names = list(self.envs.term_names)
        """The behaviour's reward terms (``info["reward/<term>"]``)."""
        first = {name: arrays[f"obs/{name}"][0] for name in self.names}
        self.observation_dict = observation_space(first)
        """One env's observation space, typed as the Dict of groups it is."""
        self.single_observation_space = self.observation_dict
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.single_action_space = action_space(self.envs.num_actions)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.render_mode = None
        self._fresh = True  # not reset yet
        self._closed = False

    def _observations(self, prefix: str = "obs/") -> dict[str, np.ndarray]:
        arrays = self.envs.arrays
        return {name: arrays[f"{prefix}{name}"].copy() for name in self.names}

    def _stage_info(self) -> dict[str, Any]:
        stages = np.full(self.num_envs, self.clock.stage.name, dtype=object)
        return {"stage": stages, "_stage": np.ones(self.num_envs, dtype=bool)}

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Start a new episode in every env; return the first observations, each (num_envs,
        *shape), and ``{"stage": ...}``.

        ``seed``: env ``i``'s generator is reseeded ``seed + i``; the first reset without one
        uses the config's ``seed``, as a run seeds its envs. Episodes under way are abandoned
        (the envs reset themselves at every episode's end, so a learner need not call this
        again; an abandoned episode's evaluator figures run into the next one's). Reward terms
        keep their lifetime memory, as in a run.
        """
        require_open(self, self._closed, "reset")
        if seed is None and self._fresh:
            seed = self.seed_base
        super().reset(seed=seed)
        if seed is not None or not self._fresh:
            state = self.envs.state_dict()
            if seed is not None:
                for i, env_state in enumerate(state["envs"]):
                    env_state["rng"] = np.random.default_rng(seed + i).bit_generator.state
            self.envs.load_state_dict(state)  # every env restores its state and resets
        self._fresh = False
        return self._observations(), self._stage_info()

    def step(
        self, actions: np.ndarray
    ) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Step every env one decision; an env whose episode ends resets in the same step.

        Args:
            actions: (num_envs, action_dim) in [-1, 1].
        Returns:
            ``(obs, rewards (num_envs,) float32, terminated (num_envs,) bool, always False,
            truncated (num_envs,) bool, info)``.
        """
        require_open(self, self._closed, "step")
        stage = self.clock.stage.name
        ended = self.envs.step_arrays(np.asarray(actions, dtype=np.float32))
        self._fresh = False
        arrays = self.envs.arrays
        terms = arrays["term_rewards"].copy()
        info: dict[str, Any] = {}
        every = np.ones(self.num_envs, dtype=bool)
        for k, name in enumerate(self.term_names):
            info[f"reward/{name}"], info[f"_reward/{name}"] = terms[:, k], every
        info.update(self._stage_info())
        for i, summary in ended:
            final_info = step_info(self.term_names, terms[i], stage)
            final_info.update(episode_info(summary))
            final_obs = {name: arrays[f"final/{name}"][i].copy() for name in self.names}
            self._add_info(info, {"final_obs": final_obs, "final_info": final_info}, i)
        result = (
            self._observations(),
            arrays["rewards"].copy(),
            np.zeros(self.num_envs, dtype=bool),
            arrays["time_outs"].copy(),
            info,
        )
        boundary, changed = self.clock.tick()
        if boundary:  # a run's iteration: one lifetime memory, the next stage
            self.envs.sync_run_memory()
            if changed:
                self.envs.set_stage(self.clock.stage.options)
            self.envs.set_age(self.clock.age_months)  # a growing body: the schedule's age
        return result

    def close_extras(self, **kwargs: Any) -> None:
        """Stop the workers, close the envs and remove the temporary folder."""
        self._closed = True
        if hasattr(self, "envs"):  # not when building them failed
            self.envs.close()
            self.setup.close()
