"""``devlearn bench``: environment steps per second and the cost of each sense."""

from __future__ import annotations

import argparse
import json
import sys

# (key, label, unit, BabyBench reference on our machine kind, our target, higher is better)
ROWS = [
    ("self_touch_steps_per_s", "self-touch env steps/s (1 process)", "/s", "400-600", ">= 2500", 1),
    ("hand_regard_steps_per_s", "hand-regard env steps/s (1 process)", "/s", "30", ">= 150", 1),
    ("physics_ms_per_step", "physics per step", "ms", "0.24", "-", 0),
    ("touch_ms_per_step", "touch per step (dense N x 3 vector)", "ms", "3", "<= 0.2", 0),
    ("touch_sparse_ms_per_step", "touch per step (sparse, self-touch)", "ms", "-", "-", 0),
    ("proprioception_ms_per_step", "proprioception per step", "ms", "-", "-", 0),
    ("render_ms_per_frame", "one 64x64 eye render", "ms", "several", "-", 0),
    ("self_touch_vec_steps_per_s_1_workers", "self-touch 16 envs, 1 worker", "/s", "-", "-", 1),
    ("self_touch_vec_steps_per_s_2_workers", "self-touch 16 envs, 2 workers", "/s", "-", "-", 1),
    ("self_touch_train_steps_per_s", "self-touch training steps/s", "/s", "-", ">= 1500", 1),
    ("hand_regard_train_steps_per_s", "hand-regard training steps/s", "/s", "-", ">= 60", 1),
    ("self_touch_update_us_per_sample_old", "self-touch update/sample, old", "us", "-", "-", 0),
    ("self_touch_update_us_per_sample", "self-touch update/sample", "us", "-", "<= 1/3 before", 0),
    ("hand_regard_update_us_per_sample_old", "hand-regard update/sample, old", "us", "-", "-", 0),
    ("hand_regard_update_us_per_sample", "hand-regard update/sample", "us", "-", "-", 0),
    ("self_touch_train_steps_per_s_old", "self-touch training, before", "/s", "-", "-", 1),
    ("hand_regard_train_steps_per_s_old", "hand-regard training, before", "/s", "-", "-", 1),
    ("build_s", "environment build", "s", "19", "< 3", 0),
    ("peak_memory_mb", "peak memory", "MB", "-", "-", 0),
]


def add_parser(subparsers) -> list[str]:
    """Register the ``bench`` sub-command."""
    p = subparsers.add_parser("bench", help="measure environment and training speed")
    p.add_argument("--json", action="store_true", help="print the figures as a JSON object")
    p.add_argument("--quick", action="store_true", help="fewer steps (rougher figures)")
    return ["bench"]


def format_table(result: dict) -> str:
    """Return the figures as a Markdown table beside the BabyBench reference."""
    lines = [
        f"devlearn bench, {result.get('date')}, {result.get('machine')}",
        "",
        "| measure | devlearn | BabyBench (reference) | target |",
        "|---|---|---|---|",
    ]
    for key, label, unit, reference, target, _ in ROWS:
        if key in result:
            value = result[key]
            if value is None:
                shown = "failed (see stderr)"
            else:
                shown = (f"{value:,.0f}" if value >= 100 else f"{value:.3g}") + f" {unit}"
            lines.append(f"| {label} | {shown} | {reference} | {target} |")
    return "\n".join(lines)


def run(args: argparse.Namespace, registry) -> int:
    """Run the measurements with progress on stderr; print a table or JSON."""
    from devlearn.bench import run_bench

    result = run_bench(
        registry, quick=args.quick, progress=lambda m: print(f"bench: {m}", file=sys.stderr)
    )
    print(json.dumps(result, indent=2) if args.json else format_table(result))
    return 0
