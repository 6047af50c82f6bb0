"""Entry point of the devlearn-curiosity distribution: registers ``rnd`` and ``forward_model``."""

from __future__ import annotations

from collections.abc import Callable

from devlearn import hookimpl
from devlearn_curiosity.forward_model import ForwardModel
from devlearn_curiosity.rnd import RND


@hookimpl
def register_learned_rewards(register: Callable[[type], None]) -> None:
    """Register :class:`RND` and :class:`ForwardModel`."""
    register(RND)
    register(ForwardModel)
