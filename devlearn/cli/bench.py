"""``devlearn bench``: environment steps per second and the cost of each sense."""

from __future__ import annotations

import argparse
import json
import sys
from typing import TYPE_CHECKING, NamedTuple

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry


class Row(NamedTuple):
    """One figure of the table (higher is better for rates, ``/s``, and fractions, ``%``)."""

    key: str
    label: str
    unit: str
    reference: str = "-"
    """BabyBench's figure on our machine kind ("-": none). Its self-touch figure is the one
    measured beside ours in one run (issue 14)."""
    target: str = "-"
    """Our target ("-": none)."""


ROWS = (
    # one environment, in one process, against the physics alone (its ceiling)
    Row("self_touch_steps_per_s", "self-touch env steps/s (1 process)", "/s", "283", ">= 4000"),
    Row(
        "self_touch_steps_per_s_per_env_observations",
        "self-touch env, per-env facts and observations",
        "/s",
    ),
    Row("self_touch_reference_steps_per_s", "self-touch env, previous code paths", "/s"),
    Row("self_touch_fraction_of_ceiling", "self-touch env / crib physics", "%", "8%", ">= 20%"),
    Row("hand_regard_steps_per_s", "hand-regard env steps/s (1 process)", "/s", "30", ">= 400"),
    Row("hand_regard_reference_steps_per_s", "hand-regard env, previous code paths", "/s"),
    Row("hand_regard_fraction_of_ceiling", "hand-regard env / sitting physics", "%"),
    Row("physics_crib_steps_per_s", "physics only, crib (the ceiling)", "/s", "3,500"),
    Row("physics_sitting_steps_per_s", "physics only, sitting (the ceiling)", "/s"),
    # one physics step and each sense
    Row("physics_ms_per_step", "physics per step", "ms", "0.24"),
    Row("touch_compiled_ms_per_step", "touch + hand contacts, compiled", "ms", "-", "<= 0.05"),
    Row("touch_reference_ms_per_step", "touch, previous numpy path", "ms", "3"),
    Row("touch_and_hands_reference_ms_per_step", "touch + hand contacts, numpy", "ms"),
    Row("touch_ms_per_step", "touch per step (dense N x 3 vector)", "ms", "3"),
    Row("touch_sparse_ms_per_step", "touch per step (sparse, self-touch)", "ms"),
    Row("proprioception_ms_per_step", "proprioception per step", "ms"),
    Row("render_ms_per_frame", "one 64x64 eye render", "ms", "several"),
    # 16 environments: batched in one process, over workers, as Gymnasium vector envs
    Row(
        "self_touch_vec_steps_per_s_in_process", "self-touch 16 envs in this process, batched", "/s"
    ),
    Row(
        "self_touch_vec_steps_per_s_in_process_per_env_observations",
        "self-touch 16 envs in this process, per-env facts and observations",
        "/s",
    ),
    Row("self_touch_vec_steps_per_s_1_workers", "self-touch 16 envs, 1 worker", "/s"),
    Row(
        "self_touch_vec_steps_per_s_2_workers",
        "self-touch 16 envs, 2 workers",
        "/s",
        "-",
        ">= 6000",
    ),
    Row(
        "self_touch_vec_2_workers_fraction_of_ceiling",
        "self-touch 16 envs, 2 workers / (2 x crib physics)",
        "%",
    ),
    Row(
        "gym_vec_steps_per_s",
        "self-touch 16 envs, 2 workers, Gymnasium vector env (devlearn.gym)",
        "/s",
    ),
    Row(
        "gym_vec_devlearn_steps_per_s",
        "self-touch 16 envs, 2 workers, DevVecEnv (same turns)",
        "/s",
    ),
    Row("gym_vec_fraction_of_devlearn", "Gymnasium vector env / DevVecEnv", "%", "-", ">= 85%"),
    # training: steps per second, decisions, the update's cost per sample
    Row("self_touch_train_steps_per_s", "self-touch training steps/s", "/s", "-", ">= 7000"),
    Row("hand_regard_train_steps_per_s", "hand-regard training steps/s", "/s", "-", ">= 60"),
    Row("self_touch_train_action_repeat", "self-touch physics steps per decision", ""),
    Row("self_touch_train_steps_per_s_k1", "self-touch training, a decision every step", "/s"),
    Row(
        "self_touch_train_steps_per_s_rollout_all_cores",
        "self-touch training, rollouts on every core (torch_threads = cores)",
        "/s",
    ),
    Row("hand_regard_train_action_repeat", "hand-regard physics steps per decision", ""),
    Row("hand_regard_train_steps_per_s_k1", "hand-regard training, a decision every step", "/s"),
    Row("self_touch_update_us_per_sample_old", "self-touch update/sample, old", "us"),
    Row("self_touch_update_us_per_sample", "self-touch update/sample", "us", "-", "<= 1/3 before"),
    Row(
        "self_touch_update_us_per_sample_1thread",
        "self-touch update/sample, 1 thread (beside SB3's, same samples)",
        "us",
    ),
    Row(
        "self_touch_update_us_per_sample_sb3_1thread",
        "SB3 PPO's update/sample, 1 thread, same network size and samples",
        "us",
    ),
    Row("hand_regard_update_us_per_sample_old", "hand-regard update/sample, old", "us"),
    Row("hand_regard_update_us_per_sample", "hand-regard update/sample", "us"),
    Row("self_touch_train_steps_per_s_old", "self-touch training, before", "/s"),
    Row(
        "hand_regard_cnn_train_steps_per_s",
        "hand-regard training, the paper's CNN (1 thread)",
        "/s",
        "-",
        ">= 300 per core",
    ),
    Row("hand_regard_cnn_update_us_per_sample", "hand-regard CNN update/sample (1 thread)", "us"),
    Row(
        "hand_regard_cnn_asym_train_steps_per_s",
        "hand-regard training, the paper's CNN actor, asymmetric critic (1 thread)",
        "/s",
        "-",
        ">= 300 per core",
    ),
    Row(
        "hand_regard_cnn_asym_update_us_per_sample",
        "hand-regard CNN actor, asymmetric critic, update/sample (1 thread)",
        "us",
    ),
    Row("hand_regard_train_steps_per_s_old", "hand-regard training, before", "/s"),
    # evaluation, building, start-up, memory
    Row(
        "self_touch_eval_s_sequential",
        "devlearn eval self_touch (random policy; episodes: self_touch_eval_episodes), one env",
        "s",
    ),
    Row(
        "self_touch_eval_s",
        "devlearn eval self_touch, the same, automatic envs and workers",
        "s",
        "-",
        "<= 1/4 of one env",
    ),
    Row("build_s", "environment build", "s", "19", "< 3"),
    Row("startup_help_s", "start-up: devlearn --help", "s", "-", "< 1.5"),
    Row("startup_plugins_s", "start-up: devlearn plugins", "s", "-", "< 1.5"),
    Row("startup_config_s", "start-up: devlearn config self_touch", "s", "-", "< 1.5"),
    Row("startup_info_s", "start-up: devlearn info self_touch", "s", "-", "< 1.5"),
    Row("peak_memory_mb", "peak memory", "MB"),
)


def format_table(result: dict) -> str:
    """Return the figures as a Markdown table beside the BabyBench reference."""
    lines = [
        f"devlearn bench, {result.get('date')}, {result.get('machine')}",
        "",
        "| measure | devlearn | BabyBench (reference) | target |",
        "|---|---|---|---|",
    ]
    for key, label, unit, reference, target in ROWS:
        if key in result:
            value = result[key]
            if value is None:
                shown = "failed (see stderr)"
            elif unit == "%":
                shown = f"{100 * value:.0f}%"
            else:
                shown = (f"{value:,.0f}" if value >= 100 else f"{value:.3g}") + f" {unit}"
            lines.append(f"| {label} | {shown} | {reference} | {target} |")
    for key in sorted(k for k in result if "_breakdown" in k and k.endswith("_ms")):
        parts = ", ".join(f"{p} {ms:.3f}" for p, ms in result[key].items() if p != "total")
        name = key.removesuffix("_ms").replace("_breakdown", "")
        lines += ["", f"{name}, ms per step ({result[key]['total']:.3f} in all): {parts}"]
    for key in sorted(k for k in result if k.endswith("_iteration_s")):
        total = result[key]["total"]
        parts = ", ".join(
            f"{p} {s:.2f} ({100 * s / total:.0f}%)" for p, s in result[key].items() if p != "total"
        )
        name = key.removesuffix("_iteration_s")
        lines += ["", f"{name}, seconds per training iteration ({total:.2f} in all): {parts}"]
    return "\n".join(lines)


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Run the measurements with progress on stderr; print a table or JSON."""
    from devlearn.bench.run import run_bench

    only = tuple(name.strip() for name in args.only.split(",") if name.strip())
    result = run_bench(
        registry,
        quick=args.quick,
        progress=lambda m: print(f"bench: {m}", file=sys.stderr),
        only=only,
    )
    print(json.dumps(result, indent=2) if args.json else format_table(result))
    return 0
