"""A rendering-free stand-in for the sitting infant: synthetic eyes with two hand discs."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from synthetic import draw

LEFT_ARM = np.arange(3, 10)
RIGHT_ARM = np.arange(10, 17)


class FakeSittingInfant:
    """17 actuators (head 0..2, left arm 3..9, right arm 10..16); each arm's first two
    actions move its hand disc in both eyes; hands leaving the view are not drawn."""

    physics_timestep = control_timestep = 0.005
    scene = "sitting"
    action_dim = 17

    def __init__(
        self,
        scene: str = "sitting",
        senses=("proprioception", "eyes"),
        episode_steps: int = 20,
        appearance: str = "mittens",
        start: str = "rest",
    ) -> None:
        self.start = start
        self.episode_steps = episode_steps
        self.appearance = appearance  # the synthetic images are the same either way
        self.actuator_groups = {"head": np.arange(3), "left_arm": LEFT_ARM, "right_arm": RIGHT_ARM}
        self.actuator_names = [f"a{i}" for i in range(17)]
        self.physics = SimpleNamespace(data=SimpleNamespace(time=0.0))
        self.last_action = np.zeros(17)
        self.hands = np.array([[20.0, 40.0], [44.0, 40.0]])

    def reset(self, rng, random_pose: bool = False, start: str | None = None) -> None:
        self.physics.data.time = 0.0
        self.hands = np.array([[20.0, 40.0], [44.0, 40.0]])

    def step(self, action) -> None:
        self.last_action = np.asarray(action, dtype=float).copy()
        self.physics.data.time += self.control_timestep
        self.hands[0] += 2.0 * self.last_action[LEFT_ARM[:2]]
        self.hands[1] += 2.0 * self.last_action[RIGHT_ARM[:2]]

    def hand_visibility(self) -> np.ndarray:
        inside = np.all((self.hands >= 0) & (self.hands < 64), axis=1)  # (2 hands,)
        return np.stack([inside, inside])

    def eyes(self) -> np.ndarray:
        hands = np.where(self.hand_visibility()[0][:, None], self.hands, np.nan)
        blocks = np.array([[12.0, 52.0], [32.0, 56.0], [52.0, 50.0]])
        return np.stack([draw(hands, blocks), draw(hands, blocks)])

    def proprioception(self) -> np.ndarray:
        return np.concatenate([self.hands.ravel() / 64, self.last_action]).astype(np.float32)

    def close(self) -> None:
        pass
