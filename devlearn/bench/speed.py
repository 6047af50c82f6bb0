"""Speed measurements: environment steps per second and the cost of each sense.

Run through ``devlearn bench``. Figures come from timing real work after a warm-up, with random
actions; nothing here is a test and nothing is asserted.
"""

from __future__ import annotations

import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from devlearn.bench_ceiling import (
    env_breakdown,
    observations_old_and_new,
    physics_ceiling,
    reference_env_steps_per_s,
    touch_old_and_new,
)
from devlearn.bench_learner import bench_update, without_user_warnings


def _per_call_ms(
    fn: Callable[[], Any], calls: int, before: Callable[[], Any] | None = None
) -> float:
    """Mean milliseconds of ``fn`` over ``calls`` calls (``before`` runs untimed each time)."""
    total = 0.0
    for _ in range(calls):
        if before is not None:
            before()
        start = time.perf_counter()
        fn()
        total += time.perf_counter() - start
    return 1000.0 * total / calls


def bench_infant(steps: int = 2000, frames: int = 100) -> dict[str, float]:
    """Physics, touch, proprioception and eye-render cost on the bare infant.

    Returns:
        ``build_s`` (crib build), ``physics_ms_per_step``, ``touch_ms_per_step`` (the dense
        (N, 3) vector), ``touch_sparse_ms_per_step`` (only the sensors that feel a force),
        ``proprioception_ms_per_step``, ``render_ms_per_frame`` (one 64x64 eye),
        ``touch_sensors``, ``contacts_per_step``.
    """
    from devlearn.infant import build_infant

    rng = np.random.default_rng(0)
    start = time.perf_counter()
    crib = build_infant("crib", senses=("touch", "proprioception", "vestibular"))
    build_s = time.perf_counter() - start
    crib.reset(rng, random_pose=True)
    actions = rng.uniform(-1, 1, (steps, crib.action_dim))
    for a in actions[:200]:  # warm-up (the compiled touch loads), reach a state with contacts
        crib.step(a)
        crib.touch()
    it = iter(actions)
    physics = _per_call_ms(lambda: crib.step(next(it)), steps)
    it = iter(actions)
    contacts = []

    def step_and_count():
        crib.step(next(it))
        contacts.append(int(crib.physics.data.ncon))

    touch = _per_call_ms(crib.touch, steps, before=step_and_count)
    it = iter(actions)
    sparse = _per_call_ms(crib.touch_sparse, steps, before=lambda: crib.step(next(it)))
    it = iter(actions)
    proprio = _per_call_ms(crib.proprioception, steps, before=lambda: crib.step(next(it)))
    crib.close()

    sitting = build_infant("sitting", senses=("proprioception", "eyes"))
    sitting.reset(rng)
    acts = rng.uniform(-1, 1, (frames + 10, sitting.action_dim))
    for a in acts[:10]:
        sitting.step(a)
        sitting.eyes()
    it = iter(acts[10:])
    render = _per_call_ms(sitting.eyes, frames, before=lambda: sitting.step(next(it))) / 2.0
    sitting.close()
    return {
        "build_s": build_s,
        "physics_ms_per_step": physics,
        "touch_ms_per_step": touch,
        "touch_sparse_ms_per_step": sparse,
        "proprioception_ms_per_step": proprio,
        "render_ms_per_frame": render,
        "touch_sensors": int(crib.skin.num_sensors),
        "contacts_per_step": float(np.mean(contacts)),
    }


@without_user_warnings
def bench_behavior_env(behavior, steps: int, reference_touch: bool = False) -> float:
    """Single-process environment steps per second of one BehaviorEnv (random actions);
    ``reference_touch``: with the numpy touch routine instead of the compiled one."""
    from devlearn.env import BehaviorEnv

    env = BehaviorEnv(behavior, seed=0)
    if reference_touch and hasattr(env.infant, "_contacts"):
        env.infant._contacts.compiled = False
    env.reset()
    rng = np.random.default_rng(0)
    rate = random_steps_per_s(env.step, rng, env.action_dim, steps, warmup=50)
    env.close()
    return rate


def random_steps_per_s(
    step, rng: np.random.Generator, action_dim: int, steps: int, warmup: int
) -> float:
    """Steps per second of ``step(action)`` on uniform random actions in [-1, 1]: ``warmup``
    untimed steps, then ``steps`` timed ones (actions drawn beforehand, outside the timing)."""
    actions = rng.uniform(-1, 1, (steps + warmup, action_dim))
    for a in actions[:warmup]:
        step(a)
    start = time.perf_counter()
    for a in actions[warmup:]:
        step(a)
    return steps / (time.perf_counter() - start)


def bench_vec_env(behavior, num_envs: int, workers: int, steps: int) -> float:
    """Environment steps per second (summed over envs) of a DevVecEnv with ``workers`` processes."""
    import torch

    from devlearn.env import DevVecEnv

    env = DevVecEnv(behavior, num_envs=num_envs, seed=0, workers=workers)
    try:
        gen = torch.Generator().manual_seed(0)
        for _ in range(10):
            env.step(torch.rand(num_envs, env.num_actions, generator=gen) * 2 - 1)
        start = time.perf_counter()
        for _ in range(steps):
            env.step(torch.rand(num_envs, env.num_actions, generator=gen) * 2 - 1)
        return steps * num_envs / (time.perf_counter() - start)
    finally:
        env.close()


def bench_training(
    behavior: str, steps: int, extra: list[str], progress: Callable[[str], None]
) -> float | None:
    """End-to-end training steps per second (collection plus PPO update) of ``devlearn run``
    with its default environments and workers.

    Reads the steps-per-second the run itself logged for its iterations after the first (which
    includes start-up costs). Returns None, after reporting the run's error through
    ``progress``, when the run fails.
    """
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run"
        cmd = [sys.executable, "-m", "devlearn.cli", "run", behavior, "--steps", str(steps)]
        cmd += ["--seed", "0", "--out", str(out), *extra]
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=1800)
        if done.returncode != 0:
            lines = (done.stderr or done.stdout).strip().splitlines()
            progress(f"{behavior} training failed: {lines[-1] if lines else done.returncode}")
            return None
        rows = [json.loads(line) for line in (out / "metrics.jsonl").read_text().splitlines()]
    rows = rows[1:] or rows
    return float(np.mean([r["steps_per_s"] for r in rows]))


def decision_rate(
    registry,
    behavior: str,
    steps: int,
    extra: list[str],
    progress: Callable[[str], None],
) -> dict[str, Any]:
    """The behaviour's default decision rate (``<behavior>_train_action_repeat``: physics steps
    per policy decision) and, beside ``<behavior>_train_steps_per_s`` measured at it, the same
    training with a decision every physics step (``<behavior>_train_steps_per_s_k1``). Both
    count physics steps per second."""
    from devlearn.training.config import default_config

    repeat = default_config(registry.behavior(behavior)).env.action_repeat
    result: dict[str, Any] = {f"{behavior}_train_action_repeat": repeat}
    if repeat > 1:
        progress(f"{behavior}: end-to-end training, a decision every physics step (K=1)")
        result[f"{behavior}_train_steps_per_s_k1"] = bench_training(
            behavior, steps, [*extra, "--set", "env.action_repeat=1"], progress
        )
    return result


OLD_LEARNER = ["network.layout=separate", "torch_threads=1", "update_threads=1"]
"""``--set`` options that train as before the shared layout and automatic threads."""


def bench_learner(behaviors: dict, quick: bool, progress: Callable[[str], None]) -> dict:
    """PPO update cost per sample and training steps/s, old learner against new, one session.

    Old: separate actor and critic, one torch thread (the defaults before the shared layout).
    New: ``devlearn run`` defaults (shared body, automatic threads; the update benchmark uses
    all cores). Keys ``<behavior>_update_us_per_sample[_old]`` and
    ``<behavior>_train_steps_per_s[_old]``; hand regard trains with 8 envs and a short
    babbling (speed does not depend on the detector's quality).
    """
    from devlearn.training.process import learner_threads

    result: dict[str, Any] = {}
    rollouts = {"self_touch": (16, 32 if quick else 128), "hand_regard": (8, 8 if quick else 32)}
    for name, (envs, steps) in rollouts.items():
        if name not in behaviors:
            continue
        for suffix, layout, threads in (("_old", "separate", 1), ("", "shared", learner_threads())):
            progress(f"{name}: PPO update, {layout} networks, {threads} thread(s)")
            behavior, repeats = behaviors[name](), 1 if quick else 2
            figures = bench_update(behavior, layout, envs, steps, repeats, threads)
            result[f"{name}_update_us_per_sample{suffix}"] = figures["update_us_per_sample"]
            result[f"{name}_inference_ms_per_step{suffix}"] = figures["inference_ms_per_step"]
    old = [arg for kv in OLD_LEARNER for arg in ("--set", kv)]
    if "self_touch" in behaviors:
        progress("self_touch: end-to-end training, old learner (separate networks, 1 thread)")
        result["self_touch_train_steps_per_s_old"] = bench_training(
            "self_touch", 8192 if quick else 32768, old, progress
        )
    if "hand_regard" in behaviors:
        progress("hand_regard: end-to-end training, old learner (separate networks, 1 thread)")
        short = ["behavior.babbling_steps=300", "behavior.correlation_threshold=0"]
        result["hand_regard_train_steps_per_s_old"] = bench_training(
            "hand_regard",
            1024 if quick else 4096,
            ["--envs", "8", *(arg for kv in short for arg in ("--set", kv)), *old],
            progress,
        )
    return result


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


def run_bench(registry, quick: bool = False, progress: Callable[[str], None] = print) -> dict:
    """Run every measurement; return the figures (see ``devlearn bench --help``)."""
    n = 300 if quick else 2000
    result_startup = {}
    for name, args in STARTUP_COMMANDS.items():
        progress(f"start-up: devlearn {' '.join(args)}")
        result_startup[f"startup_{name}_s"] = cli_startup_s(args, 1 if quick else 3)
    progress("infant: physics, touch, proprioception, eye render")
    result: dict[str, Any] = bench_infant(steps=n, frames=20 if quick else 100)
    result.update(result_startup)
    result.update(touch_old_and_new(n))
    for scene in ("crib", "sitting"):
        progress(f"{scene}: physics-only steps (the ceiling)")
        result[f"physics_{scene}_steps_per_s"] = physics_ceiling(scene, 2 * n)
    behaviors = registry.behaviors()
    for name in ("self_touch", "hand_regard"):
        if name not in behaviors:
            progress(f"{name}: not installed, skipped")
            continue
        behavior = behaviors[name]()
        progress(f"{name}: single-process environment steps, now and on the previous code paths")
        steps = n if name == "self_touch" else max(n // 10, 50)
        result[f"{name}_steps_per_s"] = bench_behavior_env(behavior, steps)
        # a behaviour that batches: both figures again, old and new alternating (best of 2)
        result.update(observations_old_and_new(behavior, steps, 20 if quick else 200))
        result[f"{name}_reference_steps_per_s"] = reference_env_steps_per_s(behavior, steps)
        key = f"physics_{behavior.scene}_steps_per_s"
        if key not in result:  # a scene other than crib and sitting (hand regard's BabyBench's)
            result[key] = physics_ceiling(behavior.scene, 2 * n)
        ceiling = result[key]
        result[f"{name}_fraction_of_ceiling"] = result[f"{name}_steps_per_s"] / ceiling
        progress(f"{name}: where a step's time goes")
        result[f"{name}_breakdown_ms"] = env_breakdown(behavior, steps)
    if "self_touch" in behaviors:
        behavior = behaviors["self_touch"]()
        for workers in (1, 2):
            progress(f"self_touch: 16 environments over {workers} worker process(es)")
            result[f"self_touch_vec_steps_per_s_{workers}_workers"] = bench_vec_env(
                behavior, num_envs=16, workers=workers, steps=20 if quick else 200
            )
        # each worker runs on its own core: the ceiling is one crib's physics per worker
        result["self_touch_vec_2_workers_fraction_of_ceiling"] = result[
            "self_touch_vec_steps_per_s_2_workers"
        ] / (2 * result["physics_crib_steps_per_s"])
        progress("self_touch: end-to-end training (devlearn run defaults)")
        result["self_touch_train_steps_per_s"] = bench_training(
            "self_touch", 8192 if quick else 32768, [], progress
        )
        result.update(decision_rate(registry, "self_touch", 8192 if quick else 32768, [], progress))
    if "hand_regard" in behaviors:
        progress("hand_regard: end-to-end training (short babbling, any correlation accepted)")
        # prepare() babbles before training (10,000 rendered steps by default); a short babble
        # finds weaker correlations, so the threshold is dropped: speed does not depend on it.
        short = ["behavior.babbling_steps=300", "behavior.correlation_threshold=0"]
        extra = ["--envs", "8", *(arg for kv in short for arg in ("--set", kv))]
        result["hand_regard_train_steps_per_s"] = bench_training(
            "hand_regard", 1024 if quick else 4096, extra, progress
        )
        result.update(
            decision_rate(registry, "hand_regard", 1024 if quick else 4096, extra, progress)
        )
    result.update(bench_learner(behaviors, quick, progress))
    usage_self = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    usage_children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    # the largest resident set of any one process (this one, a training run or a worker)
    result["peak_memory_mb"] = max(usage_self, usage_children) / 1024.0
    result["machine"] = f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores"
    result["date"] = time.strftime("%Y-%m-%d")
    return result
