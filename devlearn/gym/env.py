"""DevlearnEnv: one environment of a behaviour as a ``gymnasium.Env``."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import gymnasium
import numpy as np

from devlearn.env.behavior_env import BehaviorEnv, build_default_infant
from devlearn.env.settings import EnvSettings
from devlearn.gym.run_setup import (
    CurriculumClock,
    Overrides,
    RunSetup,
    action_space,
    as_space,
    episode_info,
    observation_space,
    require_open,
    step_info,
)

if TYPE_CHECKING:
    from devlearn.env.behavior_env import InfantFactory
    from devlearn.plugins import PluginRegistry

FRAME_HEIGHT = 256
"""Height of :meth:`DevlearnEnv.render`'s frames (each eye's 64 x 64 image shown 4x)."""


def camera_frame(infant: Any) -> np.ndarray:
    """What the infant sees and a third-person view of it, side by side: left eye, right eye
    (each scaled to :data:`FRAME_HEIGHT`), the scene's overview camera.

    Returns:
        (256, 2 * 256 + 384, 3) uint8 for 64 x 64 eyes.
    """
    eyes = np.asarray(infant.eyes())  # (2, H, W, 3)
    scale = max(FRAME_HEIGHT // eyes.shape[1], 1)
    eyes = eyes.repeat(scale, axis=1).repeat(scale, axis=2)
    view = infant.render_view(FRAME_HEIGHT * 3 // 2, eyes.shape[1])
    return np.concatenate([eyes[0], eyes[1], view], axis=1)


def with_eyes(factory: InfantFactory) -> InfantFactory:
    """``factory`` with the eyes sense added, so that :meth:`DevlearnEnv.render` can show what
    the eyes see whatever the behaviour observes (the sense only enables the eye cameras'
    renderer; the body and its physics are the same)."""

    def build(scene: str, senses: tuple[str, ...] = (), **options: Any) -> Any:
        return factory(scene, senses=tuple(dict.fromkeys((*senses, "eyes"))), **options)

    return build


class DevlearnEnv(gymnasium.Env):
    """One environment of a devlearn behaviour, as ``devlearn run``'s environments are.

    Made by ``gymnasium.make("devlearn/<Behaviour>-v0", overrides=..., preset=...)`` after
    ``import devlearn.gym`` (docs/gymnasium.md). The config goes through ``devlearn run``'s
    config path (:class:`~devlearn.gym.run_setup.RunSetup`); the env is a
    :class:`~devlearn.env.BehaviorEnv` seeded ``seed`` (the config's; ``reset(seed=S)``
    reseeds it), at the config's decision rate (``env.action_repeat`` physics steps per
    ``step``). Rewards are the sum of the behaviour's weighted reward terms, exactly what a
    run's env pays (unnormalised: normalising is the learner's business).

    Episodes end by time only: the last step of an episode has ``truncated`` True (never
    ``terminated``). ``info`` holds ``reward/<term>`` (each term's share of this step's reward)
    and ``stage`` (the curriculum stage); at an episode's end also ``episode/reward/<term>``
    and ``episode/metrics/<name>``, the episode's figures as a run logs them. The curriculum
    advances with the steps taken (:class:`~devlearn.gym.run_setup.CurriculumClock`).

    Args:
        behavior: The behaviour's registered name.
        overrides: Config values, as ``devlearn run --set`` takes them: ``{"seed": 3,
            "env.action_repeat": 5}`` or ``["seed=3"]``.
        preset: A preset of the behaviour (``devlearn run --preset``).
        render_mode: None or ``"rgb_array"`` (:meth:`render`).
        registry: Plugin registry (default: the installed plugins).
        infant_factory: Infant builder (tests); default the real infant.
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 40}

    def __init__(
        self,
        behavior: str,
        overrides: Overrides = None,
        preset: str = "",
        render_mode: str | None = None,
        *,
        registry: PluginRegistry | None = None,
        infant_factory: InfantFactory | None = None,
    ) -> None:
        if render_mode not in (None, "rgb_array"):
            raise gymnasium.error.Error(
                f"render_mode {render_mode!r} is not offered; valid: None, 'rgb_array'"
            )
        self.render_mode = render_mode
        self.setup = RunSetup(behavior, overrides, preset, registry=registry)
        cfg = self.setup.config
        factory = infant_factory or build_default_infant
        self.clock = CurriculumClock(self.setup.behavior.curriculum(), cfg)
        try:
            self.env = BehaviorEnv(
                self.setup.behavior,
                cfg.seed,
                with_eyes(factory) if render_mode else factory,
                age_months=self.clock.age_months,
                settings=EnvSettings.of(cfg.env),
            )
        except BaseException:
            self.setup.close()
            raise
        self.env.set_stage(self.clock.stage.options)
        self.observation_dict = observation_space(self.env.reset())  # from one observation
        """The observation space, typed as the Dict of groups it is."""
        self.observation_space = self.observation_dict
        self.action_space = action_space(self.env.action_dim)
        self.term_names = [term.name for term in self.env.terms]
        """The behaviour's reward terms (``info["reward/<term>"]``)."""
        decision_s = self.env.step_dt * self.env.action_repeat
        self.metadata = {**self.metadata, "render_fps": round(1.0 / decision_s)}
        self._next_obs: dict[str, np.ndarray] | None = None
        """The next episode's first observation, once the env began it by itself."""
        self._fresh = True  # not reset yet
        self._closed = False

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Start an episode: its first observation and ``{"stage": ...}``.

        ``seed`` reseeds the env's generator (initial poses; the behaviour's per-episode
        draws), as a run's env ``seed`` is seeded; the first reset without one uses the
        config's ``seed``. Later, without a seed, the episode the env began by itself when the
        last one ended is returned, so the episodes follow one another as in a run; an
        episode abandoned midway is closed unscored. Reward terms keep their memory over the
        agent's lifetime (self-touch's "first ever" touches), resets included, as in a run.
        """
        require_open(self, self._closed, "reset")
        if seed is None and self._fresh:
            seed = self.setup.config.seed
        self._fresh = False
        super().reset(seed=seed)
        if seed is not None:
            self.env.rng = self.np_random
        if seed is not None or self._next_obs is None:
            if self.env.episode_step:
                self.env.evaluator.end_episode()  # unfinished: its metrics are not reported
            self._next_obs = self.env.reset()
        obs = as_space(self._next_obs, self.observation_dict)
        self._next_obs = None
        return obs, {"stage": self.clock.stage.name}

    def step(
        self, action: np.ndarray
    ) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, Any]]:
        """One decision: ``action`` (action_dim,) in [-1, 1] held for ``env.action_repeat``
        physics steps.

        Returns:
            ``(obs, reward, terminated, truncated, info)``; at an episode's end ``obs`` is its
            last observation and ``truncated`` is True (``reset()`` then starts the next).
        """
        require_open(self, self._closed, "step")
        stage = self.clock.stage.name
        obs, reward, done, _, summary = self.env.step(np.asarray(action, dtype=np.float64))
        info = step_info(self.term_names, self.env.decision_rewards, stage)
        self._next_obs = None
        if done:
            assert self.env.final_observation is not None and summary is not None
            self._next_obs, obs = obs, self.env.final_observation
            info.update(episode_info(summary))
        boundary, changed = self.clock.tick()
        if changed:  # as a run's envs, from their next reset
            self.env.set_stage(self.clock.stage.options)
        if boundary:  # a growing body: the schedule's age, as a run's envs before an iteration
            self.env.set_age(self.clock.age_months)
        return as_space(obs, self.observation_dict), float(reward), False, bool(done), info

    def render(self) -> np.ndarray | None:
        """With ``render_mode="rgb_array"``: left eye, right eye and the third-person view of
        the scene now, (256, 896, 3) uint8 (:func:`camera_frame`); else None."""
        if self.render_mode != "rgb_array":
            return None
        return camera_frame(self.env.infant)

    def close(self) -> None:
        """Release the infant and the temporary folder (safe to call twice)."""
        if not self._closed:
            self._closed = True
            self.env.close()
            self.setup.close()
