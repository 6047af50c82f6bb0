"""The ages the infant's body can be built at, in a module that imports nothing, so that config
checks (``devlearn config --set infant.age_months=...``) read them without loading MuJoCo."""

from __future__ import annotations

import math

AGE_RANGE = (0.0, 24.0)
"""Ages (months) of the WHO tables and MIMo v2's growth curves the body is built from
(:mod:`devlearn.infant.growth`)."""


def check_age(age_months: object, option: str = "infant.age_months") -> float:
    """Return ``age_months`` as a float if the body can be built at it.

    Raises:
        ValueError: One line naming ``option`` and :data:`AGE_RANGE`: not a number, or outside.
    """
    lo, hi = AGE_RANGE
    if isinstance(age_months, int | float) and not isinstance(age_months, bool):
        if math.isfinite(age_months) and lo <= age_months <= hi:
            return float(age_months)
    raise ValueError(f"{option} must be between {lo:g} and {hi:g} months, got {age_months!r}")
