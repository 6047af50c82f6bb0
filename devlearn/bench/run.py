"""``devlearn bench``: every speed measurement in one session, and the commands' start-up.

Figures come from timing real work after a warm-up, with random actions; nothing here is a test
and nothing is asserted.
"""

from __future__ import annotations

import os
import platform
import resource
import subprocess
import sys
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from devlearn.bench.ceiling import (
    env_breakdown,
    observations_old_and_new,
    physics_ceiling,
    reference_env_steps_per_s,
    touch_old_and_new,
)
from devlearn.bench.infant import bench_infant
from devlearn.bench.iteration import bench_cnn_path
from devlearn.bench.learner import bench_learner
from devlearn.bench.speed import (
    bench_behavior_env,
    bench_evaluation,
    bench_gym_vec_env,
    bench_training,
    bench_vec_env,
    decision_rate,
)

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry

STARTUP_COMMANDS = {
    "help": ["--help"],
    "plugins": ["plugins"],
    "config": ["config", "self_touch"],
    "info": ["info", "self_touch"],
}
"""The commands whose start-up ``devlearn bench`` times (``startup_<name>_s``): none trains."""


def cli_startup_s(args: list[str], repeats: int = 3) -> float:
    """Best wall-clock seconds of ``python -m devlearn.cli ARGS`` in a fresh process over
    ``repeats`` runs: the interpreter, the imports, the plugins and the command itself."""
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "devlearn.cli", *args],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            check=False,
        )
        best = min(best, time.perf_counter() - start)
    return best


def _startup(registry: PluginRegistry, quick: bool, progress: Callable[[str], None]) -> dict:
    result = {}
    for name, args in STARTUP_COMMANDS.items():
        progress(f"start-up: devlearn {' '.join(args)}")
        result[f"startup_{name}_s"] = cli_startup_s(args, 1 if quick else 3)
    return result


def _infant(registry: PluginRegistry, quick: bool, progress: Callable[[str], None]) -> dict:
    n = 300 if quick else 2000
    progress("infant: physics, touch, proprioception, eye render")
    result: dict[str, Any] = bench_infant(steps=n, frames=20 if quick else 100)
    result.update(touch_old_and_new(n))
    for scene in ("crib", "sitting"):
        progress(f"{scene}: physics-only steps (the ceiling)")
        result[f"physics_{scene}_steps_per_s"] = physics_ceiling(scene, 2 * n)
    return result


def _envs(registry: PluginRegistry, quick: bool, progress: Callable[[str], None]) -> dict:
    n = 300 if quick else 2000
    result: dict[str, Any] = {}
    behaviors = registry.behaviors()
    for name in ("self_touch", "hand_regard"):
        if name not in behaviors:
            progress(f"{name}: not installed, skipped")
            continue
        behavior = behaviors[name]()
        progress(f"{name}: single-process environment steps, now and on the previous code paths")
        steps = n if name == "self_touch" else max(n // 10, 50)
        result[f"{name}_steps_per_s"] = bench_behavior_env(behavior, steps)
        if name == "self_touch":  # its compiled batch against each env alone (best of 2)
            result.update(observations_old_and_new(behavior, steps, 20 if quick else 200))
        result[f"{name}_reference_steps_per_s"] = reference_env_steps_per_s(behavior, steps)
        ceiling = physics_ceiling(behavior.scene, 2 * n)
        if behavior.scene not in ("crib", "sitting"):  # those two are the infant section's
            result[f"physics_{behavior.scene}_steps_per_s"] = ceiling
        result[f"{name}_fraction_of_ceiling"] = result[f"{name}_steps_per_s"] / ceiling
        progress(f"{name}: where a step's time goes")
        result[f"{name}_breakdown_ms"] = env_breakdown(behavior, steps)
    return result


def _vec(registry: PluginRegistry, quick: bool, progress: Callable[[str], None]) -> dict:
    result: dict[str, Any] = {}
    behavior = registry.behaviors()["self_touch"]()
    for workers in (1, 2):
        progress(f"self_touch: 16 environments over {workers} worker process(es)")
        result[f"self_touch_vec_steps_per_s_{workers}_workers"] = bench_vec_env(
            behavior, num_envs=16, workers=workers, steps=20 if quick else 200
        )
    # each worker runs on its own core: the ceiling is one crib's physics per worker
    crib = physics_ceiling("crib", 600 if quick else 4000)
    result["self_touch_vec_2_workers_fraction_of_ceiling"] = result[
        "self_touch_vec_steps_per_s_2_workers"
    ] / (2 * crib)
    return result


def _gym(registry: PluginRegistry, quick: bool, progress: Callable[[str], None]) -> dict:
    progress("self_touch: the Gymnasium vector env beside DevVecEnv, 16 envs, 2 workers")
    return bench_gym_vec_env("self_touch", 16, 2, 20 if quick else 200, registry=registry)


def _train(registry: PluginRegistry, quick: bool, progress: Callable[[str], None]) -> dict:
    behaviors = registry.behaviors()
    result: dict[str, Any] = {}
    if "self_touch" in behaviors:
        progress("self_touch: end-to-end training (devlearn run defaults)")
        # 26 iterations of 5,120 steps: a figure that one warm-up and the thread plan's two
        # probe iterations (one in 25 in a long run) do not skew
        steps = 8192 if quick else 131072
        result["self_touch_train_steps_per_s"] = bench_training("self_touch", steps, [], progress)
        result.update(decision_rate(registry, "self_touch", steps, [], progress))
        # the rollout's policy on every core too: the automatic plan on an idle machine before
        # rollouts beside env workers took one thread (ThreadPlan: libgomp's idle thread then
        # spun on the workers' cores)
        from devlearn.training.process import rank_cores

        cores = ["--set", f"torch_threads={rank_cores()}"]
        progress("self_touch: end-to-end training, rollouts on every core (the plan before)")
        result["self_touch_train_steps_per_s_rollout_all_cores"] = bench_training(
            "self_touch", steps, cores, progress
        )
    if "hand_regard" in behaviors:
        progress("hand_regard: end-to-end training (short babbling, any correlation accepted)")
        # prepare() babbles before training (10,000 rendered steps by default); a short babble
        # finds weaker correlations, so the threshold is dropped: speed does not depend on it.
        short = ["behavior.babbling_steps=300", "behavior.correlation_threshold=0"]
        extra = ["--envs", "8", *(arg for kv in short for arg in ("--set", kv))]
        steps = 1024 if quick else 4096
        result["hand_regard_train_steps_per_s"] = bench_training(
            "hand_regard", steps, extra, progress
        )
        result.update(decision_rate(registry, "hand_regard", steps, extra, progress))
    return result


def _eval(registry: PluginRegistry, quick: bool, progress: Callable[[str], None]) -> dict:
    result: dict[str, Any] = {"self_touch_eval_episodes": 16 if quick else 100}
    episodes = result["self_touch_eval_episodes"]
    for suffix, extra in (("_sequential", ["--envs", "1", "--workers", "0"]), ("", [])):
        how = "one env in order" if suffix else "automatic envs and workers"
        progress(f"self_touch: devlearn eval, {episodes} random-policy episodes, {how}")
        result[f"self_touch_eval_s{suffix}"] = bench_evaluation("self_touch", episodes, extra)
    return result


Section = Callable[["PluginRegistry", bool, Callable[[str], None]], dict]
SECTIONS: dict[str, tuple[Section, tuple[str, ...]]] = {
    "startup": (_startup, ()),
    "infant": (_infant, ()),
    "envs": (_envs, ()),
    "vec": (_vec, ("self_touch",)),
    "gym": (_gym, ("self_touch",)),
    "train": (_train, ()),
    "eval": (_eval, ("self_touch",)),
    "learner": (bench_learner, ()),
    "cnn": (bench_cnn_path, ("hand_regard",)),
}
"""``devlearn bench --only`` sections, in the order a full run measures them: name ->
(measurement, the behaviours it needs installed)."""


def run_bench(
    registry: PluginRegistry,
    quick: bool = False,
    progress: Callable[[str], None] = print,
    only: tuple[str, ...] = (),
) -> dict:
    """Run every measurement, or the :data:`SECTIONS` named in ``only``; return the figures
    (see ``devlearn bench --help``).

    Raises:
        UsageError: ``only`` names a section that does not exist.
    """
    from devlearn.api.errors import UsageError

    unknown = [name for name in only if name not in SECTIONS]
    if unknown:
        raise UsageError(
            f"unknown bench section(s) {', '.join(unknown)}; valid: {', '.join(SECTIONS)}"
        )
    behaviors = registry.behaviors()
    result: dict[str, Any] = {}
    for name, (measure, needs) in SECTIONS.items():
        if only and name not in only:
            continue
        missing = [b for b in needs if b not in behaviors]
        if missing:
            progress(f"{name}: {', '.join(missing)} not installed, skipped")
            continue
        result.update(measure(registry, quick, progress))
    usage_self = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    usage_children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    # the largest resident set of any one process (this one, a training run or a worker)
    result["peak_memory_mb"] = max(usage_self, usage_children) / 1024.0
    result["machine"] = f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores"
    result["date"] = time.strftime("%Y-%m-%d")
    if only:
        result["sections"] = list(only)
    return result
