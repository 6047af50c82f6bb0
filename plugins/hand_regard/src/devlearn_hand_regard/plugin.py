"""Entry point of the devlearn-hand-regard distribution: registers the hand_regard behaviour."""

from __future__ import annotations

from collections.abc import Callable

from devlearn import hookimpl
from devlearn_hand_regard.behavior import HandRegard


@hookimpl
def register_behaviors(register: Callable[[type], None]) -> None:
    """Register :class:`HandRegard`."""
    register(HandRegard)
