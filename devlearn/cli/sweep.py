"""``devlearn sweep BEHAVIOR``: train and evaluate a grid of variants times seeds, then report."""

from __future__ import annotations

import argparse
import shlex
import sys
from typing import TYPE_CHECKING

from devlearn.api.errors import UsageError
from devlearn.cli.options import add_behavior, add_overrides, add_preset

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry


def add_parser(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> list[str]:
    """Register the ``sweep`` sub-command."""
    p = subparsers.add_parser(
        "sweep",
        help="train and evaluate a grid of variants times seeds, then report",
        description="Run an experiment in one folder: every combination of --grid values times "
        "--seeds is trained (devlearn run) and evaluated (devlearn eval) in its own run folder, "
        "then devlearn report compares them. Started again, a sweep keeps finished runs and "
        "continues unfinished ones from their checkpoints. Settings can come from a TOML sweep "
        "file (--file); options given here win.",
    )
    add_behavior(p)
    p.add_argument("--file", metavar="TOML", help="sweep file with the same settings")
    p.add_argument("--out", metavar="DIR", help="the sweep folder (required here or in the file)")
    p.add_argument(
        "--grid",
        action="append",
        metavar="KEY=V1,V2",
        help="config values to try, e.g. behavior.curriculum=fixed_only,two_stage (repeatable: "
        "every combination)",
    )
    p.add_argument("--seeds", metavar="LIST", help="seeds of every combination: 1,2,3 or 1-3")
    p.add_argument("--steps", metavar="N", help="environment steps per run (e.g. 4e5)")
    p.add_argument("--envs", metavar="N", help="environments per run")
    p.add_argument(
        "--workers", metavar="N", help="env worker processes per run (default 0: in process)"
    )
    p.add_argument("--cores", metavar="N", help="cores each run holds (default: max(1, workers))")
    add_overrides(
        p,
        "config override of every run (repeatable)",
    )
    add_preset(
        p,
        "every run starts from this preset of the behaviour (e.g. paper; `devlearn "
        "config BEHAVIOR` lists them); --steps, --envs, --set and the grid apply over it",
    )
    p.add_argument("--episodes", metavar="N", help="evaluation episodes per run (default 10)")
    p.add_argument("--eval-seed", metavar="S", help="seed of the evaluations (default 0)")
    p.add_argument(
        "--eval-args", metavar="'ARGS'", help="further devlearn eval options, quoted as one"
    )
    p.add_argument("--executor", metavar="local|ray", help="where runs execute (default local)")
    p.add_argument("--jobs", metavar="N", help="local: runs at a time (default: as cores allow)")
    p.add_argument(
        "--address",
        metavar="auto|HOST:PORT",
        help="ray: the cluster to use (default: start a local Ray instance)",
    )
    p.add_argument(
        "--no-report", dest="report", action="store_false", default=None, help="skip the report"
    )
    p.add_argument(
        "--dry-run", action="store_true", help="check everything and list the runs; start nothing"
    )
    return ["sweep"]


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
