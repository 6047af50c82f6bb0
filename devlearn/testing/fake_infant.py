"""A stand-in infant and a tiny behaviour: a real training or evaluation in seconds, no MuJoCo.

rsl-rl's dummy environment idea: :class:`FakeInfant` is a point that moves by its actions
(proprioception is its position), with faults on demand (a raised error, a Ctrl-C, a killed
worker) to test how a run handles them; :func:`fake_infant_factory` builds it where
``devlearn.training.train`` or :class:`devlearn.env.BehaviorEnv` take an ``infant_factory``.
:class:`TinyBehavior` learns to move every joint to a target. devlearn's own tests and the
curiosity plugin's train with them; a plugin's learned reward or evaluator can too.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any

import numpy as np

import devlearn
from devlearn import StepContext

if TYPE_CHECKING:
    from devlearn.infant import Infant


class FakeInfant:
    """A point that moves by its actions: proprioception is its position, (action_dim,).

    ``age_months`` is recorded only (a growing run's envs rebuild it at each new age and
    :meth:`continue_from` carries the point over), so growth can be tested without MuJoCo.
    """

    physics_timestep = 0.005
    control_timestep = 0.005

    def __init__(
        self,
        scene: str,
        senses: Iterable[str] = ("proprioception",),
        eye_size: int = 8,
        *,
        episode_steps: int = 10,
        action_dim: int = 3,
        fail_after: int | None = None,
        interrupt_after: int | None = None,
        die_after: int | None = None,
        age_months: float | None = None,
    ) -> None:
        self.scene = scene
        self.age_months = age_months
        self.senses = tuple(senses)
        self.eye_size = eye_size
        self.episode_steps = episode_steps
        self.action_dim = action_dim
        self.actuator_names = [f"joint{i}" for i in range(action_dim)]
        self.fail_after = fail_after
        self.interrupt_after = interrupt_after
        self.die_after = die_after  # SIGKILL this process (use only in env worker processes)
        self.steps_taken = 0
        self.position = np.zeros(action_dim)
        self.data = SimpleNamespace(qvel=np.zeros(action_dim))
        """As MuJoCo's ``MjData``: ``qvel``, the point's velocity over its last step."""

    @property
    def start(self) -> str:
        """How episodes start unless ``reset`` is told (the real infant's ``start``): a point
        has only its rest position, ``"rest"``."""
        return "rest"

    @start.setter
    def start(self, value: str) -> None:
        if value != "rest":
            raise ValueError("this infant has no such start (it has only rest)")

    def reset(self, rng: np.random.Generator, random_pose: bool = False) -> None:
        self.position = (
            rng.uniform(-1, 1, self.action_dim) if random_pose else np.zeros(self.action_dim)
        )
        self.data.qvel = np.zeros(self.action_dim)

    def step(self, action: np.ndarray) -> None:
        self.steps_taken += 1
        if self.fail_after is not None and self.steps_taken > self.fail_after:
            raise RuntimeError("fake infant broke on purpose")
        if self.interrupt_after is not None and self.steps_taken > self.interrupt_after:
            raise KeyboardInterrupt  # as if Ctrl-C arrived mid-rollout
        if self.die_after is not None and self.steps_taken > self.die_after:
            import os
            import signal

            os.kill(os.getpid(), signal.SIGKILL)  # as if the OOM killer struck
        before = self.position
        self.position = np.clip(self.position + 0.1 * np.clip(action, -1, 1), -2, 2)
        self.data.qvel = (self.position - before) / self.physics_timestep

    def continue_from(self, other: FakeInfant) -> None:
        """Take over ``other``'s position and step count (the real infant's joint state)."""
        self.position = other.position.copy()
        self.data.qvel = other.data.qvel.copy()
        self.steps_taken = other.steps_taken

    def proprioception(self) -> np.ndarray:
        return self.position.astype(np.float32)

    def eyes(self) -> np.ndarray:
        level = np.uint8(int(127 + 60 * np.tanh(self.position[0])))
        return np.full((2, self.eye_size, self.eye_size, 3), level, dtype=np.uint8)

    def render_view(self, width: int = 320, height: int = 240) -> np.ndarray:
        frame = np.zeros((height, width, 3), dtype=np.uint8)
        x = int((np.tanh(self.position[0]) + 1) / 2 * (width - 1))
        frame[:, max(x - 2, 0) : x + 2] = 255
        return frame

    def close(self) -> None:
        pass


def fake_infant_factory(
    scene: str, senses: Iterable[str] = ("proprioception",), eye_size: int = 8, **kwargs: Any
) -> FakeInfant:
    """Build a FakeInfant; extra kwargs (episode_steps, action_dim, fail_after...) pass through."""
    return FakeInfant(scene, senses, eye_size, **kwargs)


@dataclass
class TinyConfig:
    """Options of the tiny test behaviour."""

    target: float = 0.5
    """Position every joint should reach."""
    stage_steps: int = 1000
    """Steps of the fixed-pose stage before random poses."""
    use_eyes: bool = False
    """Also observe a (2, 8, 8, 3) uint8 image (exercises multi-dimensional observations)."""
    reach_weight: float = 1.0
    """Weight of the reach term."""


class Reach(devlearn.IntrinsicReward):
    """Minus the mean distance of the joints from the target."""

    name = "reach"

    def __init__(self, target: float, weight: float = 1.0) -> None:
        super().__init__(weight)
        self.target = target

    def __call__(self, ctx: StepContext) -> float:
        return -float(np.mean(np.abs(ctx.observations["proprioception"] - self.target)))


class StepCounter(devlearn.IntrinsicReward):
    """Pays 0; counts every step of the environment's lifetime (state survives resume)."""

    name = "counter"

    def __init__(self) -> None:
        super().__init__(0.0)
        self.count = 0

    def __call__(self, ctx: StepContext) -> float:
        self.count += 1
        return 1.0

    def state_dict(self) -> dict[str, Any]:
        return {"count": self.count}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.count = int(state["count"])


class CloseEvaluator(devlearn.Evaluator):
    """Share of steps with every joint within 0.2 of the target."""

    mergeable = True  # merge() below: devlearn eval may play its episodes in several envs

    def __init__(self, target: float) -> None:
        self.target = target
        self.close_steps = self.steps = self.episodes = 0
        self.episode_close = self.episode_steps = 0

    def record(self, ctx: StepContext) -> None:
        close = bool(np.all(np.abs(ctx.observations["proprioception"] - self.target) < 0.2))
        self.episode_close += int(close)
        self.episode_steps += 1

    def end_episode(self) -> dict[str, float]:
        result = {"close": self.episode_close / max(self.episode_steps, 1)}
        self.episodes += 1
        self.close_steps += self.episode_close
        self.steps += self.episode_steps
        self.episode_close = self.episode_steps = 0
        return result

    def summary(self) -> dict[str, Any]:
        return {"episodes": self.episodes, "close": self.close_steps / max(self.steps, 1)}

    def merge(self, later: devlearn.Evaluator) -> None:
        assert isinstance(later, CloseEvaluator)
        self.close_steps += later.close_steps
        self.steps += later.steps
        self.episodes += later.episodes

    def write_artifacts(self, out_dir: Path) -> list[Path]:
        path = out_dir / "close.txt"
        devlearn.write_text_atomically(path, f"{self.close_steps}/{self.steps}\n")
        return [path]


TINY_TRAIN_DEFAULTS: dict[str, Any] = {
    "ppo.num_steps_per_env": 8,
    "ppo.num_mini_batches": 2,
    "ppo.num_learning_epochs": 2,
    "env.action_repeat": 1,
    "ppo.schedule": "adaptive",
    "network.layout": "shared",
}
""":class:`TinyBehavior`'s run defaults: small rollouts, and the learner the core's tests and
recorded tiny runs were made with before issue #38 made issue #28's learner the core default: a
decision every physics step, the adaptive schedule, the shared layout."""


class TinyBehavior(devlearn.Behavior):
    """Move every joint of a tiny body to a target position."""

    name = "tiny"
    scene = "crib"
    config_class = TinyConfig
    about = devlearn.About(
        description="test behaviour: reach a target position",
        headline_metric="close",
        train_defaults=TINY_TRAIN_DEFAULTS,
    )

    @devlearn.per_env
    def observe(self, infant: Infant, facts: dict[str, Any]) -> dict[str, np.ndarray]:
        obs = {"proprioception": infant.proprioception()}
        if self.config.use_eyes:
            obs["eyes"] = infant.eyes()
        return obs

    def network(self) -> devlearn.NetworkSpec:
        encoders: dict[str, devlearn.SensorEncoder] = {"proprioception": devlearn.MLPEncoder((16,))}
        if self.config.use_eyes:
            encoders["eyes"] = devlearn.MLPEncoder((8,))
        return devlearn.NetworkSpec(encoders, fusion_dims=(16,), trunk_dims=(16,), init_std=0.5)

    def reward_terms(self) -> list[devlearn.IntrinsicReward]:
        return [Reach(self.config.target, self.config.reach_weight), StepCounter()]

    def curriculum(self) -> devlearn.Curriculum:
        return devlearn.Curriculum(
            [
                devlearn.Stage("fixed", self.config.stage_steps, {"random_pose": False}),
                devlearn.Stage("random", None, {"random_pose": True}),
            ]
        )

    def episode(self) -> devlearn.EpisodeSpec:
        return devlearn.EpisodeSpec(senses=("proprioception",))

    def evaluation(self) -> devlearn.EvalProtocol:
        return devlearn.EvalProtocol(evaluator=lambda training: CloseEvaluator(self.config.target))
