"""MuJoCo's OpenGL backend (``MUJOCO_GL``): which values render, and how mujoco and dm_control are
imported under a value they would refuse, so that a command that never renders (self-touch
trains on touch alone) runs whatever the variable says, and one that renders is refused with one
line naming the variable (issue #55). Imports nothing of devlearn and no mujoco (any layer may
use it)."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator

VARIABLE = "MUJOCO_GL"
"""The environment variable mujoco and dm_control pick their OpenGL backend by, when imported."""
BACKENDS = ("egl", "osmesa", "glfw")
"""The backends to name in an error: ``egl`` (headless, devlearn's default), ``osmesa``
(software, headless), ``glfw`` (a window system)."""
_RENDERS = (*BACKENDS, "", "on", "enable", "enabled", "true", "1")
"""Values both mujoco and dm_control import and render with (the last five and '' choose
``glfw``); compared exactly, as dm_control compares them."""
_OFF = ("disable", "disabled", "off", "false", "0")
"""Values both import with rendering off."""


def rendering_problem() -> str | None:
    """Why nothing can be rendered under this process's ``MUJOCO_GL``, or None where it can.

    Returns:
        One line naming the variable, its value and the valid ones.
    """
    value = os.environ.get(VARIABLE)
    if value is None or value in _RENDERS:
        return None
    valid = f"{', '.join(BACKENDS[:-1])} or {BACKENDS[-1]}"
    if value in _OFF:
        return f"{VARIABLE}={value} turns rendering off, and this renders; set it to {valid}"
    return (
        f"{VARIABLE}={value!r} is not an OpenGL backend MuJoCo knows; set it to {valid} "
        "(egl: headless, the default), or unset it"
    )


@contextlib.contextmanager
def importable() -> Iterator[None]:
    """Within the block ``MUJOCO_GL`` holds a value mujoco and dm_control import with: one they
    would refuse (raising at import, a 44-line traceback before anything else ran) is replaced
    by ``disable`` for the imports, then restored, so that nothing renders in this process and
    a render is refused (:func:`rendering_problem`). Child processes see the value as given."""
    value = os.environ.get(VARIABLE)
    if value is None or value in _RENDERS or value in _OFF:
        yield
        return
    os.environ[VARIABLE] = "disable"
    try:
        yield
    finally:
        os.environ[VARIABLE] = value
