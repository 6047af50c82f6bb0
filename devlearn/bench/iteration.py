"""Where one training iteration's time goes (``devlearn bench``; figures, never asserted).

Each part is timed alone, in this process, and scaled to one iteration of the run's config
(``num_envs`` x ``ppo.num_steps_per_env`` decisions of ``env.action_repeat`` physics steps,
then one PPO update), as a run stepping its environments in its own process (``--workers 0``,
as issue #29's CNN runs did) spends it:

- collection, from one instrumented environment
  (:func:`~devlearn.bench.ceiling.env_breakdown`): ``physics`` (every physics step),
  ``touch`` (the compiled contact routine), ``render`` (both eyes), ``facts`` (the
  behaviour's facts beyond the senses: hand regard's detector and the hands' motion),
  ``observe``, ``rewards`` and ``env`` (bookkeeping and resets), all but the physics once per
  decision for a behaviour whose facts render (``episode().facts_every_physics_step`` False),
  else once per physics step; and ``inference``, the actor and the critic on the batch of
  observations, as the runner acts;
- the update, one ``alg.update()`` on a random rollout of the run's size with clocks around
  autograd's backward pass (``update_backward``) and the optimiser (gradient clipping, Adam's
  step and zeroing the gradients: ``update_optimizer``); the rest of it is ``update_forward``
  (the networks' forward passes on every mini-batch, the losses).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

from devlearn.bench.ceiling import env_breakdown
from devlearn.bench.learner import build_learner, collect_random, run_config
from devlearn.bench.speed import without_user_warnings

if TYPE_CHECKING:
    from devlearn.api.behavior import Behavior
    from devlearn.plugins import PluginRegistry
    from devlearn.training.ppo import UniqueParamPPO

ITERATION_PARTS = (
    "physics",
    "touch",
    "render",
    "facts",
    "observe",
    "rewards",
    "env",
    "inference",
    "update_forward",
    "update_backward",
    "update_optimizer",
)
"""The parts of :func:`iteration_profile`, in the order of an iteration."""


@contextmanager
def _clocked(owner: Any, name: str, spent: dict[str, float], part: str) -> Iterator[None]:
    """Add the seconds every call of ``owner.name`` takes to ``spent[part]`` while inside."""
    original = getattr(owner, name)

    def timed(*args: Any, **kwargs: Any) -> Any:
        start = time.perf_counter()
        try:
            return original(*args, **kwargs)
        finally:
            spent[part] += time.perf_counter() - start

    setattr(owner, name, timed)
    try:
        yield
    finally:
        setattr(owner, name, original)


def timed_update(alg: UniqueParamPPO) -> dict[str, float]:
    """Seconds of one ``alg.update()`` (its rollout storage full): ``update_forward``,
    ``update_backward`` and ``update_optimizer`` (see the module's docstring)."""
    import torch

    spent = {"update_backward": 0.0, "update_optimizer": 0.0}
    start = time.perf_counter()
    with (
        _clocked(torch.Tensor, "backward", spent, "update_backward"),
        _clocked(torch.nn.utils, "clip_grad_norm_", spent, "update_optimizer"),
        _clocked(alg.optimizer, "step", spent, "update_optimizer"),
        _clocked(alg.optimizer, "zero_grad", spent, "update_optimizer"),
    ):
        alg.update()
    total = time.perf_counter() - start
    return {"update_forward": total - sum(spent.values()), **spent}


@without_user_warnings
def iteration_profile(
    behavior: Behavior,
    overrides: list[str],
    env_steps: int,
    update_steps: int | None = None,
    threads: int = 1,
    prepare: Callable[[UniqueParamPPO], None] | None = None,
    registry: PluginRegistry | None = None,
) -> dict[str, Any]:
    """Seconds per iteration of each of :data:`ITERATION_PARTS` for a run of ``behavior``
    under ``overrides`` (``--set`` values), and their total.

    Args:
        behavior: The behaviour, configured as the run's (e.g. ``config.policy = "cnn"``).
        overrides: The run's ``--set`` values beyond the behaviour's defaults.
        env_steps: Instrumented environment steps behind the collection's parts.
        update_steps: Steps per env of the timed update's rollout (default: the run's
            ``ppo.num_steps_per_env``; fewer for a quick figure: its forward and backward
            passes are scaled up to the run's rollout).
        threads: torch threads of the inference and the update (the CNN runs used 1).
        prepare: Called with the learner before it is timed (a code path to compare).
        registry: Where the behaviour is registered (default: the installed plugins).
    Returns:
        Part -> seconds per iteration, ``total``, and ``update_us_per_sample`` (the update's
        seconds per rollout sample, in microseconds).
    """
    from devlearn.training.process import update_threads

    cfg = run_config(behavior, overrides, registry)
    envs, decisions, repeat = cfg.num_envs, cfg.ppo.num_steps_per_env, cfg.env.action_repeat
    step = env_breakdown(behavior, env_steps)  # ms per physics step, part by part
    once = repeat if behavior.episode().facts_every_physics_step else 1
    per_decision = {"physics": repeat * step["physics"], "render": once * step["eyes"]}
    for part in ("touch", "facts", "rewards", "env"):
        per_decision[part] = once * step[part]
    per_decision["observe"] = step["observe"]  # the decision's last physics step only
    result = {part: ms * envs * decisions / 1000.0 for part, ms in per_decision.items()}
    steps = update_steps or decisions
    alg, observations = build_learner(behavior, cfg.network.layout, envs, steps, registry=registry)
    if prepare is not None:
        prepare(alg)
    with update_threads(threads):
        best: dict[str, float] = {}
        inference = float("inf")
        for k in range(2):  # a warm-up, then the timed one
            ms = collect_random(alg, observations, steps)
            parts = timed_update(alg)
            if k:
                best, inference = parts, ms
    # forward and backward passes grow with the rollout; the optimiser steps once per
    # mini-batch whatever its size
    scale = decisions / steps
    result["inference"] = inference * decisions / 1000.0
    result.update({part: seconds * scale for part, seconds in best.items()})
    result["update_optimizer"] = best["update_optimizer"]
    result["total"] = sum(result[part] for part in ITERATION_PARTS)
    update = sum(best.values())
    result["update_us_per_sample"] = 1e6 * update / (envs * steps)
    result["threads"] = float(threads)
    return result


CNN_RUN = ["behavior.policy=cnn", "behavior.critic=same"]
"""The paper's network for hand regard (each eye's image through a CNN) for the actor and the
critic alike, with the behaviour's other defaults: issue #29's CNN runs (8 envs x 64 decisions
of 5 physics steps, separate actor and critic, 5 epochs of 4 mini-batches); ``--preset paper``'s
critic."""
CNN_ASYMMETRIC_RUN = ["behavior.policy=cnn", "behavior.critic=proprio"]
"""The same actor with an asymmetric critic (proprioception and the detector's output, no eye
CNNs): ``behavior.policy=cnn``'s default since issue #40."""
CNN_PATHS = {"hand_regard_cnn": CNN_RUN, "hand_regard_cnn_asym": CNN_ASYMMETRIC_RUN}
"""The CNN paths ``devlearn bench`` measures in one run: figure-name prefix -> ``--set``."""


def bench_cnn_path(
    registry: PluginRegistry, quick: bool, progress: Callable[[str], None]
) -> dict[str, Any]:
    """Hand regard's CNN paths (:data:`CNN_PATHS`: the paper's network, and its actor with the
    asymmetric critic), each: every part's seconds per iteration (``PREFIX_iteration_s``,
    :func:`iteration_profile` on one torch thread, as the CNN runs trained), the update's
    cost per rollout sample (``PREFIX_update_us_per_sample``) and end-to-end training steps/s
    (``PREFIX_train_steps_per_s``, a short ``devlearn run``)."""
    from devlearn.bench.speed import bench_training

    result: dict[str, Any] = {}
    short = ["behavior.babbling_steps=300", "behavior.correlation_threshold=0", "torch_threads=1"]
    for prefix, overrides in CNN_PATHS.items():
        # the behaviour built on the config the run resolves (its --set values checked)
        behavior = registry.create("hand_regard")
        behavior = type(behavior)(run_config(behavior, overrides, registry).behavior)
        progress(f"{prefix}: where an iteration's time goes")
        profile = iteration_profile(
            behavior, overrides, 20 if quick else 200, 8 if quick else None, registry=registry
        )
        result[f"{prefix}_iteration_s"] = {k: profile[k] for k in (*ITERATION_PARTS, "total")}
        result[f"{prefix}_update_us_per_sample"] = profile["update_us_per_sample"]
        progress(f"{prefix}: end-to-end training")
        settings = [arg for kv in (*overrides, *short) for arg in ("--set", kv)]
        result[f"{prefix}_train_steps_per_s"] = bench_training(
            "hand_regard", 2560 if quick else 3 * 2560, ["--envs", "8", *settings], progress
        )
    return result
