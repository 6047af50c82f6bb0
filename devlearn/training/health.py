"""Learner health: the figures that say whether PPO is still learning, and the warning when not.

Measured on every rollout (issue #28): the policy's spread (min / mean / max over action
dimensions), the share of saturated means (mean actions at or past +-0.995: a clipped action
that no longer varies with the state), the value function's explained variance, and the
learning rate and surrogate loss that PPO reports. Three signatures of a learner that has
stopped learning print one warning line each, once, naming what was seen and what to try:

- ``stalled``: surrogate loss >= 0 with the learning rate at its floor, for
  :data:`PATIENCE` iterations running (the adaptive schedule has given up);
- ``saturated``: most means saturated for :data:`PATIENCE` iterations;
- ``spread``: the mean spread pinned within 2% of a bound of the head for :data:`PATIENCE`
  iterations.
"""

from __future__ import annotations

from typing import Any

import torch

SATURATED = 0.995
"""A mean action whose magnitude reaches this is saturated."""
PATIENCE = 20
"""Iterations a signature must last before it is reported."""
LR_FLOOR = 1e-5
"""rsl-rl's adaptive schedule never goes below this learning rate."""

ADVICE = {
    "stalled": (
        "the surrogate loss has stayed >= 0 with the learning rate at its floor {lr:.0e}: PPO "
        "no longer improves the policy; try ppo.normalize_rewards=true, network.head=gaussian, "
        "network.layout=separate or ppo.schedule=fixed"
    ),
    "saturated": (
        "{share:.0%} of the policy's mean actions are saturated at +-1: the head pushes them "
        "past the action bound and they no longer depend on the state; try network.head=gaussian"
    ),
    "spread": (
        "the policy's spread is pinned at its {bound} bound ({value:.3g}); try a different "
        "ppo.entropy_coef or the head's bounds (network.min_std, behavior.max_std)"
    ),
}


def rollout_health(storage: Any) -> dict[str, float]:
    """Spread, saturation and explained variance of one rollout (before the update).

    Args:
        storage: rsl-rl's RolloutStorage after ``compute_returns`` (its ``distribution_params``
            are the collecting policy's (mean, std), (T, N, A) each).
    Returns:
        ``health/std_min``, ``health/std_mean``, ``health/std_max`` (per-dimension spreads,
        averaged over the rollout), ``health/saturated`` (share of mean entries with
        magnitude >= :data:`SATURATED`) and ``health/explained_variance`` of the values.
    """
    mean, std = storage.distribution_params[0], storage.distribution_params[1]
    per_dim = std.reshape(-1, std.shape[-1]).mean(dim=0)
    returns, values = storage.returns.flatten(), storage.values.flatten()
    var = returns.var(unbiased=False)
    explained = 1.0 - (returns - values).var(unbiased=False) / var if var > 0 else torch.nan
    return {
        "health/std_min": float(per_dim.min()),
        "health/std_mean": float(per_dim.mean()),
        "health/std_max": float(per_dim.max()),
        "health/saturated": float((mean.abs() >= SATURATED).float().mean()),
        "health/explained_variance": float(explained),
    }


class HealthWatch:
    """Watches each iteration's metrics row for the collapse signatures (module docstring).

    Args:
        std_bounds: (lower, upper) bounds of the head's spread; an upper of 0 is unbounded.
        adaptive: Whether the learning rate follows rsl-rl's adaptive schedule, whose floor
            is the "stalled" signature (a linear schedule goes below it by design).
    """

    def __init__(self, std_bounds: tuple[float, float], adaptive: bool = True) -> None:
        self.std_bounds = std_bounds
        self.adaptive = adaptive
        self.runs = {name: 0 for name in ADVICE}
        self.warnings: list[str] = []
        """Every warning given, in order (the end-of-run summary repeats them)."""

    def check(self, row: dict[str, Any]) -> list[str]:
        """Update the counts with one iteration's row; return the warnings new this time."""
        lo, hi = self.std_bounds
        surrogate = row.get("loss/surrogate")
        lr = row.get("learning_rate")
        std = row.get("health/std_mean")
        seen: dict[str, dict[str, Any]] = {}
        if (
            self.adaptive
            and surrogate is not None
            and lr is not None
            and surrogate >= 0
            and lr <= LR_FLOOR * 1.01
        ):
            seen["stalled"] = {"lr": lr}
        if (row.get("health/saturated") or 0.0) > 0.5:
            seen["saturated"] = {"share": row["health/saturated"]}
        if std is not None and std <= lo * 1.02:
            seen["spread"] = {"bound": "lower", "value": std}
        elif std is not None and hi > 0 and std >= hi * 0.98:
            seen["spread"] = {"bound": "upper", "value": std}
        new = []
        for name in ADVICE:
            self.runs[name] = self.runs[name] + 1 if name in seen else 0
            if self.runs[name] == PATIENCE:
                step = row.get("step", "?")
                message = f"learner warning at step {step}: " + ADVICE[name].format(**seen[name])
                self.warnings.append(message)
                new.append(message)
        return new
