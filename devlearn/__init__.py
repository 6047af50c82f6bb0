"""devlearn: developmental reinforcement learning with a simulated infant.

The public API for behaviour plugins: the four interfaces (:class:`Behavior`,
:class:`SensorEncoder`, :class:`IntrinsicReward`, :class:`Curriculum`), the learned-reward kind
(:class:`LearnedReward`) and the hook marker
:data:`hookimpl`. See ``docs/writing-a-plugin.md``.
"""

from __future__ import annotations

import os

from devlearn.lazy import lazy_getattr

# MuJoCo picks its GL backend when first imported: headless EGL (no display needed) unless the
# user chose another. Set here, before anything can import mujoco through devlearn.
os.environ.setdefault("MUJOCO_GL", "egl")
# OpenMP threads that wait for work sleep instead of spinning, so torch's idle threads do not
# take cores from the env workers (read when torch loads: effective if devlearn comes first).
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

# The public names load on first use (PEP 562), so that ``import devlearn`` and the commands
# that neither train nor evaluate (``devlearn --help``, ``plugins``, ``config``) do not pay for
# torch; a plugin that imports only Behavior, IntrinsicReward, Curriculum... stays light too.
_PUBLIC = {
    "BatchContext": "devlearn.rewards",
    "BatchedIntrinsicReward": "devlearn.rewards",
    "Behavior": "devlearn.behavior",
    "Curriculum": "devlearn.curriculum",
    "Evaluator": "devlearn.behavior",
    "IntrinsicReward": "devlearn.rewards",
    "LearnedReward": "devlearn.learned",
    "LearnedRewardConfig": "devlearn.learned",
    "MLPEncoder": "devlearn.sensors",
    "NetworkSpec": "devlearn.network_spec",
    "SensorEncoder": "devlearn.sensors",
    "Stage": "devlearn.curriculum",
    "StepContext": "devlearn.rewards",
    "Transitions": "devlearn.learned",
    "hookimpl": "devlearn.hookspecs",
}


__getattr__ = lazy_getattr("devlearn", _PUBLIC, globals())


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))


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
