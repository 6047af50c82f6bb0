"""Speed measurements: environment and training steps per second.

Part of ``devlearn bench`` (:func:`devlearn.bench.run.run_bench`). Figures come from timing real
work after a warm-up, with random actions; nothing here is a test and nothing is asserted.
"""

from __future__ import annotations

import functools
import json
import subprocess
import sys
import tempfile
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, ParamSpec, TypeVar

import numpy as np

if TYPE_CHECKING:
    from devlearn.api.behavior import Behavior
    from devlearn.plugins import PluginRegistry

P = ParamSpec("P")
R = TypeVar("R")


def without_user_warnings(function: Callable[P, R]) -> Callable[P, R]:
    """Run ``function`` with UserWarnings silenced: a speed figure of an unprepared behaviour
    (hand regard's uncalibrated detector) does not depend on what it would perceive."""

    @functools.wraps(function)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            return function(*args, **kwargs)

    return wrapper


@without_user_warnings
def bench_behavior_env(behavior: Behavior, steps: int, reference_touch: bool = False) -> float:
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
    step: Callable[[np.ndarray], object],
    rng: np.random.Generator,
    action_dim: int,
    steps: int,
    warmup: int,
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


def bench_vec_env(behavior: Behavior, num_envs: int, workers: int, steps: int) -> float:
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


def bench_gym_vec_env(
    behavior: str,
    num_envs: int,
    workers: int,
    steps: int,
    registry: PluginRegistry | None = None,
) -> dict[str, float]:
    """Physics steps per second (summed over envs) of the Gymnasium vector env
    (:class:`~devlearn.gym.vector.DevlearnVectorEnv`: numpy in and out, Gymnasium's info built
    every step) beside :func:`bench_vec_env`'s DevVecEnv (the runner's: torch in and out), with
    the same behaviour config, envs and workers, a decision every physics step
    (``env.action_repeat=1``, where a step's own overhead weighs most) and random actions. Each
    figure is the better of two turns, the two alternating, so that a burst of other work on
    the machine does not favour either.

    Returns:
        ``gym_vec_steps_per_s``, ``gym_vec_devlearn_steps_per_s`` (DevVecEnv, the same turns)
        and ``gym_vec_fraction_of_devlearn`` (their ratio; issue #45's target: at least 0.85).
    """
    from devlearn.gym.vector import DevlearnVectorEnv

    rates: dict[str, list[float]] = {"gym": [], "devlearn": []}
    for _ in range(2):
        envs = DevlearnVectorEnv(
            behavior, num_envs, workers, {"env.action_repeat": 1, "seed": 0}, registry=registry
        )
        prepared = envs.setup.behavior  # the same config (and prepared files) for DevVecEnv
        try:
            envs.reset()
            rng = np.random.default_rng(0)
            shape = (num_envs, envs.envs.num_actions)
            for _ in range(10):
                envs.step(rng.uniform(-1, 1, shape).astype(np.float32))
            start = time.perf_counter()
            for _ in range(steps):
                envs.step(rng.uniform(-1, 1, shape).astype(np.float32))
            rates["gym"].append(steps * num_envs / (time.perf_counter() - start))
            rates["devlearn"].append(bench_vec_env(prepared, num_envs, workers, steps))
        finally:
            envs.close()
    gym, ours = max(rates["gym"]), max(rates["devlearn"])
    return {
        "gym_vec_steps_per_s": gym,
        "gym_vec_devlearn_steps_per_s": ours,
        "gym_vec_fraction_of_devlearn": gym / ours,
    }


def bench_training(
    behavior: str, steps: int, extra: list[str], progress: Callable[[str], None]
) -> float | None:
    """End-to-end training steps per second (collection plus PPO update) of ``devlearn run``
    with its default environments and workers: :func:`training_rate` of the run's metrics.
    Returns None, after reporting the run's error through ``progress``, when the run fails.
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
    return training_rate(rows)


def training_rate(rows: list[dict[str, Any]]) -> float:
    """Physics steps per second of training from a run's metrics rows: the steps of every
    iteration after the first (whose collection includes start-up costs) over their collection
    and update seconds. Totals, not the mean of the iterations' rates: the thread plan's probe
    iterations (:class:`~devlearn.training.process.ThreadPlan`) are slower, and a run's rate is
    its steps over its time."""
    kept = rows[1:] or rows
    steps = [b["step"] - a["step"] for a, b in zip(rows, rows[1:])] or [rows[0]["step"]]
    seconds = sum(r["collect_s"] + r["update_s"] for r in kept)
    return float(sum(steps) / max(seconds, 1e-9))


def decision_rate(
    registry: PluginRegistry,
    behavior: str,
    steps: int,
    extra: list[str],
    progress: Callable[[str], None],
) -> dict[str, Any]:
    """The behaviour's default decision rate (``<behavior>_train_action_repeat``: physics steps
    per policy decision) and, beside ``<behavior>_train_steps_per_s`` measured at it, the same
    training with a decision every physics step (``<behavior>_train_steps_per_s_k1``). Both
    count physics steps per second."""
    from devlearn.config.resolve import RunRequest, resolve_config

    repeat = resolve_config(RunRequest(behavior), registry).env.action_repeat
    result: dict[str, Any] = {f"{behavior}_train_action_repeat": repeat}
    if repeat > 1:
        progress(f"{behavior}: end-to-end training, a decision every physics step (K=1)")
        result[f"{behavior}_train_steps_per_s_k1"] = bench_training(
            behavior, steps, [*extra, "--set", "env.action_repeat=1"], progress
        )
    return result


def bench_evaluation(behavior: str, episodes: int, extra: list[str]) -> float | None:
    """Wall-clock seconds of ``devlearn eval BEHAVIOR --policy random --episodes N`` as a user
    runs it (a fresh process: imports, environments, workers and episodes), with ``extra``
    options (``--envs``, ``--workers``). None when the command fails."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "devlearn.cli", "eval", behavior, "--policy", "random"]
        cmd += ["--episodes", str(episodes), "--out", str(Path(tmp) / "eval"), *extra]
        start = time.perf_counter()
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=3600)
        took = time.perf_counter() - start
    return took if done.returncode == 0 else None
