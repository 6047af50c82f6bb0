"""The IntrinsicReward interface: one small, documented, stateful reward term."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from devlearn.infant import Infant


@dataclass
class StepContext:
    """What a reward term sees after one control step of one environment.

    Attributes:
        infant: The simulated infant after the step (read-only use: senses, contacts).
        observations: The behaviour's observations for this step, name -> array (unbatched).
        facts: Behaviour-computed facts for this step (e.g. ``"touched"``: (68,) bool,
            ``"hand_contacts"``: (2, 68) bool, ``"hand_count"``: int). Computed once per step by
            :meth:`devlearn.Behavior.facts` and shared by all terms.
        step: Index of this step inside the episode, starting at 0.
        last_step: True on the episode's final step (time-out); terms paying at episode end
            (e.g. balance) pay here.
        stage: Options of the current curriculum stage (e.g. ``{"active_arms": ["left"]}``).
    """

    infant: Infant | None
    observations: dict[str, np.ndarray]
    facts: dict[str, Any]
    step: int
    last_step: bool
    stage: dict[str, Any] = field(default_factory=dict)


class IntrinsicReward(ABC):
    """A single intrinsic reward term, computed inside one environment.

    One instance lives in each environment, so its memory (e.g. "touched before") is that
    environment's. The environment sums ``weight * term(ctx)`` over the behaviour's terms and
    logs each term's per-episode sum separately under ``reward/<name>``.

    Subclasses set ``name`` and implement :meth:`__call__`; stateful terms override
    :meth:`reset` (per-episode memory) and :meth:`state_dict` / :meth:`load_state_dict`
    (lifetime memory that must survive ``devlearn run --resume``).

    A reward that is a model trained on batches of transitions (novelty, prediction error) is
    a :class:`~devlearn.learned.LearnedReward` instead: it lives in the learner, not here.
    """

    name: str = "reward"
    """Name used in logs (``reward/<name>``) and config."""

    def __init__(self, weight: float = 1.0) -> None:
        self.weight = float(weight)

    @abstractmethod
    def __call__(self, ctx: StepContext) -> float:
        """Return this term's unweighted reward for one step (a Python float)."""

    def reset(self) -> None:
        """Start a new episode: forget per-episode memory, keep lifetime memory."""

    def state_dict(self) -> dict[str, Any]:
        """Return everything needed to resume this term (picklable, numpy allowed)."""
        return {}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`state_dict` returned."""
