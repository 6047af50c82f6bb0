"""EnvSettings: the settled values every environment of a run steps with, in one frozen object."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from devlearn.env.motor_noise import check_noise


@dataclass(frozen=True)
class EnvSettings:
    """What a run's config settled for its environments (its ``env`` section), made once by
    whoever builds the envs (the run from its resolved config, ``devlearn eval`` from the
    policy's) and handed unchanged down the layers: :class:`~devlearn.env.vec_env.DevVecEnv`,
    :class:`~devlearn.env.workers.WorkerPool`, each worker, :func:`~devlearn.env.workers.make_envs`
    and every :class:`~devlearn.env.behavior_env.BehaviorEnv`, which reads it from here, so
    that the runner and the envs read one value. Frozen: nothing below changes it.

    The body's age is not here: it is where a growing run is (``set_age`` changes it), not a
    setting.
    """

    action_repeat: int = 1
    """Physics steps per decision: one action held over them, their rewards summed
    (``env.action_repeat``; :func:`~devlearn.env.behavior_env.step_batch`). Must divide the
    episode length (checked where the body is built)."""

    episode_seconds: float | None = None
    """Simulated seconds per episode, overriding the behaviour's
    (:meth:`~devlearn.api.behavior.Behavior.episode_seconds`) and the infant's (5 s); None:
    theirs. ``devlearn eval --session S`` sets it: whole sessions without a reset. Converted
    with the body's physics step, it must be a whole number of decisions (checked where the
    body is built)."""

    action_noise_std: float = 0.0
    """Standard deviation of the motor noise added to every action, per actuator, in action
    units (``env.action_noise_std``; 0: none, :mod:`devlearn.env.motor_noise`)."""

    action_noise_beta: float = 0.88
    """The motor noise's spectral exponent: its power falls as f^-beta
    (``env.action_noise_beta``)."""

    @classmethod
    def of(cls, env: Any, episode_seconds: float | None = None) -> EnvSettings:
        """The settings a run config's ``env`` section (:class:`devlearn.config.EnvConfig`)
        gives, with an evaluation's session length: the one place they are read from it."""
        return cls(
            int(env.action_repeat),
            episode_seconds,
            float(env.action_noise_std),
            float(env.action_noise_beta),
        )

    def __post_init__(self) -> None:
        if isinstance(self.action_repeat, bool) or not isinstance(self.action_repeat, int):
            raise TypeError(f"action_repeat must be an int, got {self.action_repeat!r}")
        if self.episode_seconds is not None and not self.episode_seconds > 0:
            raise ValueError(f"episode_seconds must be above 0, got {self.episode_seconds!r}")
        check_noise(self.action_noise_std, self.action_noise_beta)
