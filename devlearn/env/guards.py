"""Reward and observation guards: a non-finite or huge value stops the run, named where it began."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numba
import numpy as np

from devlearn.api.errors import UsageError

REWARD_BOUND = 1e6
"""Largest allowed magnitude of one reward term's (unweighted) value per step."""
OBSERVATION_BOUND = 1e6
"""Largest allowed magnitude of any element of a floating-point observation (integer
observations, e.g. uint8 images, are bounded by their dtype and not checked)."""


class GuardError(UsageError):
    """A reward term or observation produced a value that is NaN, infinite or beyond its bound.

    Attributes:
        kind: ``"reward term"`` or ``"observation"``.
        name: The term's or observation's name.
        value: The offending value (the first bad element for an array).
        env_index: Index of the environment on this rank.
        step: For a reward term the control step inside the episode (0-based); for an
            observation the observation's index inside the episode (0: the one after reset).
    """

    def __init__(self, kind: str, name: str, value: float, env_index: int, step: int) -> None:
        self.kind, self.name, self.value = kind, name, float(value)
        self.env_index, self.step = int(env_index), int(step)
        bound = REWARD_BOUND if kind == "reward term" else OBSERVATION_BOUND
        verb = "returned" if kind == "reward term" else "holds"
        super().__init__(
            f"{kind} '{name}' {verb} {self.value!r} in env {self.env_index} at episode step "
            f"{self.step} (values must be finite with magnitude <= {bound:g})"
        )

    # crosses the worker-process boundary intact
    def __reduce__(self) -> tuple[type[GuardError], tuple[Any, ...]]:
        return GuardError, (self.kind, self.name, self.value, self.env_index, self.step)


class TermError(GuardError):
    """A reward term raised an exception instead of returning a value; stops the run like a
    :class:`GuardError` (the last good state is saved), naming the term, the environment and
    the step.

    Attributes:
        error: The exception's type and message (``ZeroDivisionError: division by zero``).
        env_index: The environment's index on this rank (-1 for a batched term, which is
            called once for the whole batch).
    """

    def __init__(self, name: str, error: str, env_index: int, step: int) -> None:
        self.kind, self.name, self.value, self.error = "reward term", name, float("nan"), error
        self.env_index, self.step = int(env_index), int(step)
        where = f"env {self.env_index}" if self.env_index >= 0 else "a batch of envs"
        UsageError.__init__(
            self, f"reward term '{name}' raised {error} in {where} at episode step {self.step}"
        )

    def __reduce__(self) -> tuple[type[GuardError], tuple[Any, ...]]:
        return TermError, (self.name, self.error, self.env_index, self.step)

    @classmethod
    def wrap(cls, name: str, exc: BaseException, env_index: int, step: int) -> TermError:
        """The error for ``exc`` raised by term ``name`` (its message cut to one line)."""
        text = " ".join(str(exc).split())
        text = text if len(text) <= 200 else text[:197] + "..."
        return cls(
            name, f"{type(exc).__name__}: {text}" if text else type(exc).__name__, env_index, step
        )


def check_reward(name: str, value: float, env_index: int, step: int) -> float:
    """Return ``value`` if it is finite with ``abs(value) <= REWARD_BOUND``.

    Args:
        name: The reward term's name.
        value: Its unweighted value for this step.
        env_index: The environment's index on this rank.
        step: Step inside the episode.
    Raises:
        GuardError: Naming the term, the environment and the step.
    """
    if not abs(value) <= REWARD_BOUND:  # also False for NaN
        raise GuardError("reward term", name, value, env_index, step)
    return value


def reward_within_bound(values: np.ndarray) -> bool:
    """True when every element of a float64 array of term values is finite with magnitude at
    most :data:`REWARD_BOUND` (one compiled pass)."""
    return bool(
        _all_within(np.ascontiguousarray(values, dtype=np.float64).reshape(-1), REWARD_BOUND)
    )


def check_observations(obs: Mapping[str, np.ndarray], env_index: int, step: int) -> None:
    """Check one env's floating-point observations elementwise (finite, ``<= OBSERVATION_BOUND``).

    Raises:
        GuardError: Naming the observation, the environment and the step.
    """
    for name, value in obs.items():
        array = np.asarray(value)
        if array.dtype.kind in "fc" and not observation_within_bound(array):
            bad = ~(np.abs(array) <= OBSERVATION_BOUND)
            raise GuardError("observation", name, array[bad].flat[0].real, env_index, step)


def observation_within_bound(array: np.ndarray) -> bool:
    """True when every element of a floating-point array is finite with magnitude at most
    :data:`OBSERVATION_BOUND` (one compiled pass for float32/float64, numpy otherwise)."""
    if array.dtype == np.float32 or array.dtype == np.float64:
        return bool(_all_within(array.reshape(-1), OBSERVATION_BOUND))
    return bool((np.abs(array) <= OBSERVATION_BOUND).all())


@numba.njit(cache=True, nogil=True)
def _all_within(flat: np.ndarray, bound: float) -> bool:
    # |x| <= bound is False for NaN. A float32 element widens exactly to float64, and the
    # bound (1e6) is a float32 number, so this agrees with numpy's float32 comparison.
    for x in flat:
        if not abs(x) <= bound:
            return False
    return True
