"""One environment: an infant body driven by a behaviour's observations, rewards and metrics."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from devlearn.env.guards import check_observations, check_reward
from devlearn.rewards import StepContext

if TYPE_CHECKING:
    from devlearn.behavior import Behavior

InfantFactory = Callable[..., Any]
"""``factory(scene, senses=...) -> Infant``; defaults to :func:`devlearn.infant.build_infant`."""


def build_default_infant(scene: str, senses: tuple[str, ...]) -> Any:
    """Build the real infant (imported lazily so this module imports without it)."""
    from devlearn.infant import build_infant

    return build_infant(scene, senses=senses)


class BehaviorEnv:
    """A single sub-environment: one infant, one behaviour's reward terms and one evaluator.

    The environment resets itself: after ``infant.episode_steps`` steps the episode times out,
    its summary is returned as ``episode_info`` and a new episode begins (random initial pose
    when the stage options say ``random_pose``).

    Args:
        behavior: The behaviour (this env's own instance; it may keep per-env state).
        seed: Seed of this env's numpy Generator (initial poses).
        infant_factory: ``factory(scene, senses=...) -> Infant``; tests pass a fake one.
        training: Passed to ``behavior.evaluator`` (False for ``devlearn eval``).
        index: This env's index on its rank (named by the reward and observation guards).
    """

    def __init__(
        self,
        behavior: Behavior,
        seed: int,
        infant_factory: InfantFactory | None = None,
        training: bool = True,
        index: int = 0,
    ) -> None:
        self.behavior = behavior
        self.index = index
        factory = infant_factory or build_default_infant
        self.infant = factory(behavior.scene, senses=tuple(behavior.senses))
        self.rng = np.random.default_rng(seed)
        self.terms = behavior.reward_terms()
        self.evaluator = behavior.evaluator(training=training)
        self.stage: dict[str, Any] = dict(behavior.curriculum().stage.options)
        self.action_dim = int(self.infant.action_dim)
        self.episode_steps = int(self.infant.episode_steps)
        self.step_dt = float(self.infant.control_timestep)
        self.episode_step = 0
        self._sums = {term.name: 0.0 for term in self.terms}

    def reset(self) -> dict[str, np.ndarray]:
        """Start a new episode; return its first observations (name -> array)."""
        self.infant.reset(self.rng, random_pose=bool(self.stage.get("random_pose", False)))
        for term in self.terms:
            term.reset()
        self.episode_step = 0
        self._sums = {term.name: 0.0 for term in self.terms}
        obs = self.behavior.observe(self.infant, self.behavior.facts(self.infant))
        check_observations(obs, self.index, 0)
        return obs

    def step(
        self, action: np.ndarray
    ) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, float] | None]:
        """Advance one control step.

        Args:
            action: (action_dim,) policy action; clipped to [-1, 1].
        Returns:
            ``(obs, reward, done, time_out, episode_info)``. On the episode's last step ``done``
            and ``time_out`` are True, ``obs`` is the first observation of the next episode and
            ``episode_info`` holds ``reward/<term>`` (weighted per-episode sums) and
            ``metrics/<name>`` (evaluator); otherwise ``episode_info`` is None.
        Raises:
            GuardError: A term's value or an observation is NaN, infinite or beyond its bound
                (:mod:`devlearn.env.guards`).
        """
        action = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)
        self.infant.step(self.behavior.process_action(action, self.stage))
        facts = self.behavior.facts(self.infant)
        obs = self.behavior.observe(self.infant, facts)
        check_observations(obs, self.index, self.episode_step + 1)
        last_step = self.episode_step == self.episode_steps - 1
        ctx = StepContext(self.infant, obs, facts, self.episode_step, last_step, self.stage)
        reward = 0.0
        for term in self.terms:
            raw = check_reward(term.name, float(term(ctx)), self.index, self.episode_step)
            value = term.weight * raw
            self._sums[term.name] += value
            reward += value
        self.evaluator.record(ctx)
        self.episode_step += 1
        if not last_step:
            return obs, reward, False, False, None
        info = {f"reward/{name}": total for name, total in self._sums.items()}
        info.update({f"metrics/{k}": float(v) for k, v in self.evaluator.end_episode().items()})
        return self.reset(), reward, True, True, info

    def set_stage(self, options: dict[str, Any]) -> None:
        """Use a curriculum stage's options from now on (``random_pose`` from the next reset)."""
        self.stage = dict(options)

    def state_dict(self) -> dict[str, Any]:
        """Return the resumable state: every reward term's state, the rng and the stage."""
        return {
            "terms": {term.name: term.state_dict() for term in self.terms},
            "rng": self.rng.bit_generator.state,
            "stage": dict(self.stage),
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore :meth:`state_dict`'s output (call :meth:`reset` afterwards)."""
        for term in self.terms:
            if term.name in state["terms"]:
                term.load_state_dict(state["terms"][term.name])
        self.rng.bit_generator.state = state["rng"]
        self.stage = dict(state["stage"])

    def close(self) -> None:
        """Release the infant's resources."""
        self.infant.close()
