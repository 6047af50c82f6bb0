"""Whether this process can render, asked before anything renders: under an unusable
``MUJOCO_GL`` a command that renders (a behaviour that sees through the infant's eyes, a video,
a picture) is refused with one line, before a worker starts or a file is written, and one that
never renders runs (:mod:`devlearn.gl_backend`)."""

from __future__ import annotations

from collections.abc import Sequence

from devlearn.api.errors import UsageError
from devlearn.gl_backend import rendering_problem

RENDERED_SENSES = ("eyes",)
"""Senses the infant renders (its eye cameras); the others are read from the physics."""


def require_rendering(what: str) -> None:
    """Refuse ``what`` (``--video``, a behaviour's eyes) when nothing can be rendered.

    Raises:
        UsageError: ``MUJOCO_GL`` names no backend (one line naming it and the valid values).
    """
    if problem := rendering_problem():
        raise UsageError(f"{what} needs rendering: {problem}")


def check_senses_render(senses: Sequence[str], who: str) -> None:
    """:func:`require_rendering` when ``senses`` include a rendered one (``who``: whose
    senses, for the message)."""
    if any(sense in RENDERED_SENSES for sense in senses):
        require_rendering(f"{who} (the infant's eyes)")
