"""Entry point of the example plugin: registers the hand_to_mouth behaviour."""

from __future__ import annotations

from collections.abc import Callable

import devlearn
from devlearn_hand_to_mouth.behavior import HandToMouth


@devlearn.hookimpl
def register_behaviors(register: Callable[[type], None]) -> None:
    """Register :class:`HandToMouth` with devlearn."""
    register(HandToMouth)
