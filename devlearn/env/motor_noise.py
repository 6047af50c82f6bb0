"""Time-correlated motor noise with a power-law spectrum, added to the actions an env applies.

Infants' hand-velocity spectra fall as f^-beta, beta 0.69 at 8 weeks to 0.88 at 30 weeks
(Ernst, Lopez, Hoffmann and Triesch, arXiv 2606.16590); spontaneous movement is "pink",
not the white noise of a Gaussian policy. :class:`PowerLawNoise` is one such stream per
actuator, in action units (a fraction of each motor's maximum torque), sampled at every
physics step and added to the policy's action before it is clipped to [-1, 1]
(``env.action_noise_std``, ``env.action_noise_beta``; off by default).

How: a sum of first-order (AR(1), Ornstein-Uhlenbeck) processes, one per octave of corner
frequencies from :data:`LOWEST_HZ` to the Nyquist frequency, plus a white one. A Lorentzian
with corner f_k is flat below f_k and falls as f^-2 above it, so a sum of them with weights
growing as f_k^(1-beta) per octave is f^-beta between the lowest and highest corners (for
0 <= beta < 2). The weights are fitted by non-negative least squares to the exact
discrete-time spectra of the AR(1) processes at the body's physics step, which removes the
sum's bias near the band's edges (fitted weights give a Welch slope within 0.01 of beta from
0.05 Hz to 90 Hz at 200 Hz; the closed-form f_k^(1-beta) weights overshoot by ~0.05). The
process is stationary from its first sample (its state starts drawn from the stationary
law), never reset: an env's noise runs on through episode resets and whole sessions, and
its state is saved with the env's, so a resumed run continues the same stream.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

LOWEST_HZ = 0.01
"""Lowest corner frequency (Hz): below it the spectrum is flat. 100 s, a third of a 5-minute
observation session (the infants' spectra are measured within such sessions)."""

BETA_MAX = 2.0
"""Exclusive upper bound of beta: a sum of Lorentzians (each f^-2 at high frequency) cannot
fall faster than f^-2."""

NOISE_STREAM = 57
"""Mixed into an env's seed for its noise generator, so the noise is a stream of its own: the
env's initial poses (its generator seeded with the seed alone) are the same with or without
noise."""


def check_noise(std: float, beta: float, where: str = "env.action_noise") -> None:
    """Raise ValueError naming the wrong value and the valid range.

    Args:
        std: The noise's standard deviation per actuator (action units): from 0 (off) to 1.
        beta: The spectrum's exponent: from 0 (white) to below :data:`BETA_MAX`.
        where: The options' common prefix in messages.
    """
    if isinstance(std, bool) or not 0.0 <= float(std) <= 1.0:
        raise ValueError(f"{where}_std must be from 0 (off) to 1 (action units), got {std!r}")
    if isinstance(beta, bool) or not 0.0 <= float(beta) < BETA_MAX:
        raise ValueError(
            f"{where}_beta must be from 0 (white noise) to below {BETA_MAX:g}, got {beta!r}"
        )


@functools.lru_cache(maxsize=16)
def power_law_filters(beta: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """The AR(1) processes whose sum has a spectrum ~ f^-beta, sampled every ``dt`` seconds.

    Args:
        beta: The exponent, 0 <= beta < 2.
        dt: Seconds between samples (the body's physics step).
    Returns:
        ``(a, variance)``, each (K,): the processes' coefficients x <- a x + noise (one per
        octave of corners from :data:`LOWEST_HZ` to the Nyquist frequency, a white one with a
        = 0 last), and their stationary variances, summing to 1. Processes the fit leaves at
        weight 0 are dropped.
    """
    from scipy.optimize import nnls  # scipy is slow to import; only where noise is on

    nyquist = 0.5 / dt
    octaves = int(np.floor(np.log2(nyquist / LOWEST_HZ))) + 1
    corners = LOWEST_HZ * 2.0 ** np.arange(octaves)
    a = np.append(np.exp(-2.0 * np.pi * corners * dt), 0.0)
    # each unit-variance AR(1)'s spectrum (1 - a^2) / |1 - a e^{-i w}|^2 on a log grid of the
    # band, divided by the target f^-beta: weights making the sum 1 there make it ~ f^-beta
    grid = np.geomspace(2.0 * LOWEST_HZ, nyquist, 200)
    z = np.exp(-2j * np.pi * grid * dt)
    spectra = (1.0 - a[None] ** 2) / np.abs(1.0 - a[None] * z[:, None]) ** 2
    weights, _ = nnls(spectra * grid[:, None] ** beta, np.ones(len(grid)))
    keep = weights > 0
    return a[keep], weights[keep] / weights[keep].sum()


class PowerLawNoise:
    """Gaussian noise with a power spectrum ~ f^-beta, one independent stream per actuator.

    Each call advances every stream by one sample (one physics step of ``dt`` seconds) and
    returns it; the standard deviation of every stream is ``std``.

    Args:
        dims: Streams (the body's actuators).
        std: Standard deviation of each stream (action units: a fraction of max torque).
        beta: Spectral exponent (0: white; infants: 0.69 to 0.88).
        dt: Seconds per sample (the body's physics step).
        seed: The env's seed (mixed with :data:`NOISE_STREAM`).
    """

    def __init__(self, dims: int, std: float, beta: float, dt: float, seed: int) -> None:
        check_noise(std, beta)
        self.dims, self.std, self.beta, self.dt = int(dims), float(std), float(beta), float(dt)
        self.a, variance = power_law_filters(self.beta, self.dt)
        # innovations of x <- a x + sqrt(var (1 - a^2)) eps keep each process at its variance
        self._gain = np.sqrt(variance * (1.0 - self.a**2))[:, None]
        self._a = self.a[:, None]
        self.rng = np.random.default_rng([int(seed), NOISE_STREAM])
        self.state = self.rng.standard_normal((len(self.a), self.dims)) * np.sqrt(variance)[:, None]
        """(K, dims): each process's current value, started from its stationary law."""

    def __call__(self) -> np.ndarray:
        """The next sample: (dims,) float64."""
        eps = self.rng.standard_normal(self.state.shape)
        self.state *= self._a
        self.state += self._gain * eps
        return self.std * self.state.sum(axis=0)

    def sample(self, steps: int) -> np.ndarray:
        """The next ``steps`` samples, (steps, dims): the same as ``steps`` calls."""
        return np.stack([self() for _ in range(int(steps))])

    def state_dict(self) -> dict[str, Any]:
        """The processes' values and the generator's state (picklable)."""
        return {"state": self.state.copy(), "rng": self.rng.bit_generator.state}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore :meth:`state_dict`'s output: the stream continues where it was saved."""
        saved = np.asarray(state["state"], dtype=np.float64)
        if saved.shape != self.state.shape:
            raise ValueError(
                f"saved motor noise has shape {saved.shape}; this env's is {self.state.shape} "
                "(another beta, physics step or body)"
            )
        self.state = saved.copy()
        self.rng.bit_generator.state = state["rng"]
