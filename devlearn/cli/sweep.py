"""``devlearn sweep BEHAVIOR``: train and evaluate a grid of variants times seeds, then report."""

from __future__ import annotations

import argparse
import shlex
import sys
from typing import TYPE_CHECKING

from devlearn.api.errors import UsageError

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Build the sweep, check it, run it (or list it with --dry-run)."""
    from devlearn.cli.run import interrupt_at_once
    from devlearn.sweep import build_spec, plan_sweep, run_sweep

    options = {
        "out": args.out,
        "grid": args.grid,
        "seeds": args.seeds,
        "steps": args.steps,
        "envs": args.envs,
        "workers": args.workers,
        "cores": args.cores,
        "overrides": args.overrides,
        "preset": args.preset,
        "episodes": args.episodes,
        "eval_seed": args.eval_seed,
        "eval_args": None if args.eval_args is None else _split(args.eval_args),
        "executor": args.executor,
        "jobs": args.jobs,
        "address": args.address,
        "report": args.report,
    }
    spec = build_spec(args.behavior, options, args.file)
    global_args = [a for name in args.disable_plugin for a in ("--disable-plugin", name)]
    if args.dry_run:
        from devlearn.sweep.bookkeeping import check_folder

        runs = plan_sweep(spec, registry, global_args)
        check_folder(spec)
        if spec.executor == "local":  # as the real sweep will, before it starts anything
            from devlearn.sweep.executors import local_cores

            local_cores(spec.train.cores_per_run)
        for planned in runs:
            job = planned.job
            argv = ["devlearn", *global_args, "run", job.behavior, "--out", str(job.run_dir)]
            argv += ["--config", str(job.config_path)]
            print(f"{job.name}: {shlex.join(argv)}  # {' '.join(job.settings)}")
        print(f"{len(runs)} runs in {spec.out}; nothing started (--dry-run)")
        return 0
    with interrupt_at_once():
        return run_sweep(spec, registry, global_args=global_args, command=shlex.join(sys.argv))


def _split(text: str) -> list[str]:
    try:
        return shlex.split(text)
    except ValueError as exc:
        raise UsageError(f"--eval-args does not parse: {exc}") from None
