"""devlearn: developmental reinforcement learning with a simulated infant.

The public API for behaviour plugins, defined in :mod:`devlearn.api` and re-exported here: the
four interfaces (:class:`Behavior`, :class:`SensorEncoder`, :class:`IntrinsicReward`,
:class:`Curriculum`), the learned-reward kind (:class:`LearnedReward`), the hook marker
:data:`hookimpl`, the infant a behaviour reads (:class:`Infant`, :func:`build_infant`), and
devlearn's atomic file writer (:func:`write_text_atomically`, :func:`write_atomically`), through
which a plugin writes its files too.
Plugins import only ``devlearn``, ``devlearn.api`` and ``devlearn.testing`` (checked by
``lint-imports``, docs/architecture.md). See ``docs/writing-a-plugin.md``.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

from devlearn.lazy import lazy_getattr

if TYPE_CHECKING:  # the same names, for type checkers (which do not run __getattr__)
    from devlearn.api.batching import EnvBatch, per_env
    from devlearn.api.behavior import (
        Behavior,
        BehaviorConfig,
        Evaluator,
        RunMetrics,
        evaluation_stage,
    )
    from devlearn.api.capabilities import (
        About,
        Artifacts,
        EpisodeHooks,
        EpisodeSpec,
        EvalProtocol,
    )
    from devlearn.api.curriculum import Curriculum, Stage
    from devlearn.api.errors import UsageError
    from devlearn.api.hookspecs import hookimpl
    from devlearn.api.learned import LearnedReward, LearnedRewardConfig, Transitions
    from devlearn.api.network_spec import NetworkSpec
    from devlearn.api.rewards import (
        BatchContext,
        BatchedFromPerEnv,
        BatchedIntrinsicReward,
        IntrinsicReward,
        RewardTermCfg,
        StepContext,
    )
    from devlearn.api.sensors import MLPEncoder, SensorEncoder
    from devlearn.api.stats import episode_stats
    from devlearn.files import write_atomically, write_text_atomically
    from devlearn.infant import Infant, build_infant

# MuJoCo picks its GL backend when first imported: headless EGL (no display needed) unless the
# user chose another. Set here, before anything can import mujoco through devlearn.
os.environ.setdefault("MUJOCO_GL", "egl")
# Without a GPU, EGL renders on Mesa's llvmpipe: with no rasteriser threads it draws each small
# eye image in the calling thread (the same pixels, ~20% less per render, and runs side by side
# do not share its thread pool). GPU drivers ignore it.
os.environ.setdefault("LP_NUM_THREADS", "0")
# OpenMP's wait policy is libgomp's default (a waiting thread spins a while, then sleeps), not
# PASSIVE as before issue #54: a sleeping thread woken for each of a PPO update's thousands of
# small operations made a 2-thread self-touch update take 0.34 s against 0.16 s spinning (and
# 0.24 s on one thread), so training kept one thread. Rollouts beside env workers use one
# thread (ThreadPlan), so no idle thread spins on the workers' cores; on a machine shared with
# other programs, ThreadPlan falls back to one thread, or `export OMP_WAIT_POLICY=PASSIVE`
# before starting devlearn (docs/benchmarks.md).

# The public names load on first use (PEP 562), so that ``import devlearn`` and the commands
# that neither train nor evaluate (``devlearn --help``, ``plugins``, ``config``) do not pay for
# torch; a plugin that imports only Behavior, IntrinsicReward, Curriculum... stays light too.
_PUBLIC = {
    "About": "devlearn.api.capabilities",
    "Artifacts": "devlearn.api.capabilities",
    "EnvBatch": "devlearn.api.batching",
    "EpisodeHooks": "devlearn.api.capabilities",
    "EpisodeSpec": "devlearn.api.capabilities",
    "EvalProtocol": "devlearn.api.capabilities",
    "per_env": "devlearn.api.batching",
    "BatchContext": "devlearn.api.rewards",
    "BatchedFromPerEnv": "devlearn.api.rewards",
    "BatchedIntrinsicReward": "devlearn.api.rewards",
    "Behavior": "devlearn.api.behavior",
    "BehaviorConfig": "devlearn.api.behavior",
    "evaluation_stage": "devlearn.api.behavior",
    "Curriculum": "devlearn.api.curriculum",
    "Evaluator": "devlearn.api.behavior",
    "Infant": "devlearn.infant",
    "IntrinsicReward": "devlearn.api.rewards",
    "LearnedReward": "devlearn.api.learned",
    "LearnedRewardConfig": "devlearn.api.learned",
    "MLPEncoder": "devlearn.api.sensors",
    "NetworkSpec": "devlearn.api.network_spec",
    "RewardTermCfg": "devlearn.api.rewards",
    "RunMetrics": "devlearn.api.behavior",
    "SensorEncoder": "devlearn.api.sensors",
    "Stage": "devlearn.api.curriculum",
    "StepContext": "devlearn.api.rewards",
    "Transitions": "devlearn.api.learned",
    "UsageError": "devlearn.api.errors",
    "build_infant": "devlearn.infant",
    "episode_stats": "devlearn.api.stats",
    "hookimpl": "devlearn.api.hookspecs",
    "write_atomically": "devlearn.files",
    "write_text_atomically": "devlearn.files",
}


__getattr__ = lazy_getattr("devlearn", _PUBLIC, globals())


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))


__version__ = "0.1.0"

__all__ = [
    "About",
    "Artifacts",
    "EnvBatch",
    "EpisodeHooks",
    "EpisodeSpec",
    "EvalProtocol",
    "per_env",
    "BatchContext",
    "BatchedFromPerEnv",
    "BatchedIntrinsicReward",
    "Behavior",
    "BehaviorConfig",
    "evaluation_stage",
    "Curriculum",
    "Evaluator",
    "Infant",
    "IntrinsicReward",
    "LearnedReward",
    "LearnedRewardConfig",
    "MLPEncoder",
    "NetworkSpec",
    "RewardTermCfg",
    "RunMetrics",
    "SensorEncoder",
    "Stage",
    "StepContext",
    "Transitions",
    "UsageError",
    "build_infant",
    "episode_stats",
    "hookimpl",
    "write_atomically",
    "write_text_atomically",
]
