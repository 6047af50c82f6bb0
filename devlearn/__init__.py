"""devlearn: developmental reinforcement learning with a simulated infant.

The public API for behaviour plugins: the four interfaces (:class:`Behavior`,
:class:`SensorEncoder`, :class:`IntrinsicReward`, :class:`Curriculum`), the learned-reward kind
(:class:`LearnedReward`) and the hook marker
:data:`hookimpl`. See ``docs/writing-a-plugin.md``.
"""

from __future__ import annotations

import os

# MuJoCo picks its GL backend when first imported: headless EGL (no display needed) unless the
# user chose another. Set here, before anything can import mujoco through devlearn.
os.environ.setdefault("MUJOCO_GL", "egl")
# OpenMP threads that wait for work sleep instead of spinning, so torch's idle threads do not
# take cores from the env workers (read when torch loads: effective if devlearn comes first).
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

from devlearn.behavior import Behavior, Evaluator
from devlearn.curriculum import Curriculum, Stage
from devlearn.hookspecs import hookimpl
from devlearn.learned import LearnedReward, LearnedRewardConfig, Transitions
from devlearn.network_spec import NetworkSpec
from devlearn.rewards import BatchContext, BatchedIntrinsicReward, IntrinsicReward, StepContext
from devlearn.sensors import MLPEncoder, SensorEncoder

__version__ = "0.1.0"

__all__ = [
    "BatchContext",
    "BatchedIntrinsicReward",
    "Behavior",
    "Curriculum",
    "Evaluator",
    "IntrinsicReward",
    "LearnedReward",
    "LearnedRewardConfig",
    "MLPEncoder",
    "NetworkSpec",
    "SensorEncoder",
    "Stage",
    "StepContext",
    "Transitions",
    "hookimpl",
]
