"""Spread of a sample: mean, standard deviation and Student-t confidence interval (SciPy)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

CONFIDENCE = 0.95
"""Confidence level of every interval devlearn reports."""


def mean_ci(values: Sequence[float], confidence: float = CONFIDENCE) -> dict[str, float | None]:
    """Mean, sample standard deviation and the t-interval of the mean of ``values``.

    The interval is ``scipy.stats.t.interval(confidence, n - 1, mean, sem)`` with
    ``sem = std(ddof=1) / sqrt(n)``: the usual interval for the mean of n independent draws
    (episodes of one evaluation, or seeds of one variant).

    Args:
        values: (n,) sample.
        confidence: Level of the interval.
    Returns:
        ``{"n", "mean", "std", "ci_low", "ci_high"}``; ``std`` and the interval are None when
        n < 2 (no spread can be estimated from one value). A sample without spread (all values
        equal) gets the degenerate interval [mean, mean].
    """
    from scipy import stats

    x = np.asarray(values, dtype=np.float64)
    n = int(x.size)
    if n == 0:
        return {"n": 0, "mean": None, "std": None, "ci_low": None, "ci_high": None}
    mean = float(x.mean())
    if n < 2:
        return {"n": 1, "mean": mean, "std": None, "ci_low": None, "ci_high": None}
    std = float(x.std(ddof=1))
    if std == 0.0:
        return {"n": n, "mean": mean, "std": 0.0, "ci_low": mean, "ci_high": mean}
    low, high = stats.t.interval(confidence, n - 1, loc=mean, scale=stats.sem(x))
    return {"n": n, "mean": mean, "std": std, "ci_low": float(low), "ci_high": float(high)}


def episode_stats(name: str, values: Sequence[float]) -> dict[str, float | None]:
    """Per-episode spread of one metric, keyed for an eval JSON.

    Returns:
        ``episode_<name>_mean``, ``_std``, ``_ci_low`` and ``_ci_high`` (95% t-interval).
    """
    s = mean_ci(values)
    return {f"episode_{name}_{k}": s[k] for k in ("mean", "std", "ci_low", "ci_high")}
