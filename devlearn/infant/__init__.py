"""The simulated infant: body, skin, senses and scenes (``build_infant``)."""

from __future__ import annotations

import os

# Headless rendering everywhere; must be set before mujoco or dm_control is imported.
os.environ.setdefault("MUJOCO_GL", "egl")
# Without a GPU, EGL renders on Mesa's llvmpipe: with no rasteriser threads it draws each small
# eye image in the calling thread (the same pixels, ~20% less per render, and runs side by side
# do not share its thread pool). GPU drivers ignore it.
os.environ.setdefault("LP_NUM_THREADS", "0")

from devlearn.gl_backend import importable  # noqa: E402

with importable():  # an unusable MUJOCO_GL stops only a command that renders (vision.py)
    import dm_control.mjcf  # noqa: F401
    import mujoco  # noqa: F401

from devlearn.infant.infant import (  # noqa: E402
    ACTUATOR_GROUPS,
    SENSES,
    Infant,
    SenseNotEnabledError,
    build_infant,
)
from devlearn.infant.regions import (  # noqa: E402
    NUM_PARTS,
    NUM_REGIONS,
    PART_NAMES,
    RegionTable,
    region_table,
)
from devlearn.infant.skin import Skin  # noqa: E402
from devlearn.infant.vision import HAND_LABELS  # noqa: E402

__all__ = [
    "ACTUATOR_GROUPS",
    "HAND_LABELS",
    "NUM_PARTS",
    "NUM_REGIONS",
    "PART_NAMES",
    "SENSES",
    "Infant",
    "RegionTable",
    "SenseNotEnabledError",
    "Skin",
    "build_infant",
    "region_table",
]
