"""Motor babbling: random actions on the sitting infant, recording what it sees and feels.

Paper sec. II-B2: "a 10,000-step random action phase to collect a dataset of proprioception,
vision, and actions trajectories". The recording feeds :func:`calibration.calibrate`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SIDES = ("left", "right")


@dataclass
class BabblingData:
    """One babbling recording of T steps (the state after each step).

    Attributes:
        eyes: (T, 2, H, W, 3) uint8 RGB, [left eye, right eye].
        proprioception: (T, P) float32.
        actions: (T, A) float32, the random actions taken.
        arm_speed: (T, 2) float32, [left, right] arm joint-speed magnitude: the norm of the
            arm joints' velocities (the velocity part of proprioception, read through each
            arm's actuators, ``infant.actuator_groups``).
        episode: (T,) int, episode index (tracks never cross an episode boundary).
    """

    eyes: np.ndarray
    proprioception: np.ndarray
    actions: np.ndarray
    arm_speed: np.ndarray
    episode: np.ndarray

    def __len__(self) -> int:
        return len(self.eyes)


def arm_speeds(infant) -> np.ndarray:
    """Return (2,) [left, right] norms of the arm joints' velocities (rad/s, via actuators)."""
    velocity = np.asarray(infant.physics.data.actuator_velocity)
    return np.array(
        [np.linalg.norm(velocity[np.asarray(infant.actuator_groups[f"{s}_arm"])]) for s in SIDES],
        dtype=np.float32,
    )


def babble(steps: int, seed: int = 0, hold_steps: int = 8, infant=None,
           episode_steps: int | None = None) -> BabblingData:
    """Move every actuator randomly and record eyes, proprioception, actions and arm speeds.

    Each random action (uniform in [-1, 1] per actuator) is held for ``hold_steps`` steps: the
    joints are damped, so fresh noise every 5 ms would only make the arms tremble. The head
    moves too, so the scene shifts in view; the arms' speeds are what tells the hands apart.

    Args:
        steps: Steps to record (paper: 10,000).
        seed: Seed of the actions and the initial poses.
        hold_steps: Steps each random action is held (>= 1).
        infant: A sitting infant with eyes and proprioception (built and closed here if None).
        episode_steps: Steps between resets (default: the infant's episode length).
    Returns:
        The recording.
    """
    if steps < 2 or hold_steps < 1:
        raise ValueError(f"babbling needs steps >= 2 and hold_steps >= 1, got {steps}, "
                         f"{hold_steps}")
    own = infant is None
    if own:
        from devlearn.infant import build_infant

        infant = build_infant("sitting", senses=("proprioception", "eyes"))
    try:
        rng = np.random.default_rng(seed)
        length = int(episode_steps or infant.episode_steps)
        eyes, proprio, actions, speeds, episode = [], [], [], [], []
        action = np.zeros(infant.action_dim)
        for t in range(steps):
            if t % length == 0:
                infant.reset(rng, random_pose=t > 0)
            if t % hold_steps == 0:
                action = rng.uniform(-1.0, 1.0, infant.action_dim)
            infant.step(action)
            eyes.append(infant.eyes())
            proprio.append(np.asarray(infant.proprioception(), dtype=np.float32))
            actions.append(action.astype(np.float32))
            speeds.append(arm_speeds(infant))
            episode.append(t // length)
        return BabblingData(
            eyes=np.stack(eyes),
            proprioception=np.stack(proprio),
            actions=np.stack(actions),
            arm_speed=np.stack(speeds),
            episode=np.asarray(episode),
        )
    finally:
        if own:
            infant.close()
