"""Entry point of the devlearn-self-touch distribution (group ``devlearn``, name ``self_touch``)."""

from __future__ import annotations

from collections.abc import Callable

from devlearn import hookimpl
from devlearn_self_touch.behavior import SelfTouch


@hookimpl
def register_behaviors(register: Callable[[type], None]) -> None:
    """Register the :class:`SelfTouch` behaviour."""
    register(SelfTouch)
