"""The one batched path of facts and observations: what a behaviour's ``facts`` and ``observe``
see (:class:`EnvBatch`), and :func:`per_env`, the one adapter for authors who write them for one
environment at a time."""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from devlearn.api.behavior import Behavior
    from devlearn.infant import Infant


@dataclass(frozen=True)
class EnvBatch:
    """The environments a behaviour's ``facts`` and ``observe`` are called with, in batch order:
    a worker's environments after a step, or one environment after its reset.

    The core calls these methods once per step on the first environment's behaviour.

    Attributes:
        infants: (num_envs,) the environments' infants.
        behaviors: (num_envs,) each environment's own behaviour instance (one class, one
            config): where a behaviour keeps per-environment state (its episode hooks, a
            previous frame), row ``i`` reads ``behaviors[i]``'s.
    """

    infants: Sequence[Infant]
    behaviors: Sequence[Behavior]

    def __len__(self) -> int:
        return len(self.infants)

    def one(self, i: int) -> EnvBatch:
        """Environment ``i`` alone, as a batch of one."""
        return EnvBatch([self.infants[i]], [self.behaviors[i]])


def per_env(method: Callable[..., Any]) -> Callable[..., Any]:
    """Write ``facts`` or ``observe`` for one environment; the core calls it batched.

    Decorate ``def facts(self, infant) -> dict`` or ``def observe(self, infant, facts) ->
    dict[str, array]``; the result is the batched method of the contract: row ``i`` is the
    method of environment ``i``'s own behaviour (:attr:`EnvBatch.behaviors`) on its own infant
    (and facts), so per-environment state on ``self`` stays that environment's. ``observe``'s
    rows are stacked into (num_envs, *shape) arrays (one environment: a view, no copy).

    Raises:
        TypeError: ``method`` is neither ``facts`` nor ``observe``.
    """
    if method.__name__ == "facts":

        @functools.wraps(method)
        def facts(self: Behavior, batch: EnvBatch) -> list[dict[str, Any]]:
            return [method(b, infant) for b, infant in zip(batch.behaviors, batch.infants)]

        return facts
    if method.__name__ == "observe":

        @functools.wraps(method)
        def observe(
            self: Behavior, batch: EnvBatch, facts: Sequence[dict[str, Any]]
        ) -> dict[str, np.ndarray]:
            rows = [method(b, i, f) for b, i, f in zip(batch.behaviors, batch.infants, facts)]
            if len(rows) == 1:
                return {name: np.asarray(value)[None] for name, value in rows[0].items()}
            return {name: np.stack([row[name] for row in rows]) for name in rows[0]}

        return observe
    raise TypeError(f"per_env decorates a behaviour's facts or observe, not {method.__name__}")
