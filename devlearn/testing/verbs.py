"""What a behaviour does, in its own words: the facts and observations of one environment, as
the core computes them (a batch of one), for a plugin's tests."""

from __future__ import annotations

from typing import Any

import numpy as np

from devlearn.api.batching import EnvBatch
from devlearn.api.behavior import Behavior


def facts_of(behavior: Behavior, infant: Any) -> dict[str, Any]:
    """The facts ``behavior`` gives for ``infant`` in its current state (one environment:
    ``behavior`` is its own, so the call updates its per-environment state as a step would)."""
    return behavior.facts(EnvBatch([infant], [behavior]))[0]


def observations_of(
    behavior: Behavior, infant: Any, facts: dict[str, Any] | None = None
) -> dict[str, np.ndarray]:
    """The observations ``behavior`` gives for ``infant``, name -> array of one environment
    (no batch axis), from ``facts`` (default: :func:`facts_of` the infant now)."""
    if facts is None:
        facts = facts_of(behavior, infant)
    batch = behavior.observe(EnvBatch([infant], [behavior]), [facts])
    return {name: np.asarray(array)[0] for name, array in batch.items()}
