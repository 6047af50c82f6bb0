"""The simulated infant's clock, in a module that imports nothing, so that config checks
(``devlearn config --set``) can read it without loading MuJoCo: BabyBench's 5 ms physics step
and its 5-second episode (``../shared/reference/infant-and-benchmark-facts.md``, sec. 1)."""

PHYSICS_TIMESTEP = 0.005
"""Seconds per physics step (200 Hz)."""
EPISODE_STEPS = 1000
"""Physics steps per episode (5 simulated seconds)."""


def decision_rate_error(action_repeat: int, episode_steps: int = EPISODE_STEPS) -> str | None:
    """Why a decision every ``action_repeat`` physics steps cannot play episodes of
    ``episode_steps`` (the count must be at least 1 and divide the episode, or episodes would
    end inside a decision), in one line naming valid counts; None where it can.

    The one decision-rate check: ``check_config`` runs it on every resolved config, before any
    worker starts, and ``BehaviorEnv`` on the body it built (a test body's episode may be
    shorter).
    """
    if action_repeat >= 1 and episode_steps % action_repeat == 0:
        return None
    valid = [k for k in range(1, 21) if episode_steps % k == 0]
    return (
        f"env.action_repeat={action_repeat} must divide the episode ({episode_steps} physics "
        f"steps), e.g. {', '.join(map(str, valid))}"
    )


def physics_steps(seconds: float, physics_timestep: float = PHYSICS_TIMESTEP) -> int:
    """The physics steps in ``seconds`` of simulated time (300 s at 5 ms: 60,000).

    Raises:
        ValueError: ``seconds`` is not a whole number of physics steps (to a millionth of a
            step), or less than one, named with the nearest whole one.
    """
    steps = float(seconds) / float(physics_timestep)
    whole = round(steps)
    if whole < 1 or abs(steps - whole) > 1e-6:
        nearest = max(whole, 1) * float(physics_timestep)
        raise ValueError(
            f"{seconds:g} s is not a whole number of physics steps of {physics_timestep:g} s "
            f"(the nearest: {nearest:g} s)"
        )
    return int(whole)
