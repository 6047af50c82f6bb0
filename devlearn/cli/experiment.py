"""``devlearn experiment run|publish|table``: an experiment file run, published, tabulated."""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from devlearn.api.errors import UsageError

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry


def _jobs(text: str | None) -> int | None:
    if text is None:
        return None
    try:
        jobs = int(text)
    except ValueError:
        raise UsageError(f"--jobs must be an integer, got '{text}'") from None
    if jobs < 1:
        raise UsageError(f"--jobs must be at least 1, got {jobs}")
    return jobs


def _run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    from devlearn.cli.run import interrupt_at_once
    from devlearn.experiment import (
        check_experiment_folder,
        describe_plan,
        plan_experiment,
        read_experiment,
        run_experiment,
    )

    spec = read_experiment(args.file)
    jobs = _jobs(args.jobs)
    global_args = [a for name in args.disable_plugin for a in ("--disable-plugin", name)]
    if args.dry_run:
        plan = plan_experiment(spec, args.out, registry, global_args)
        check_experiment_folder(spec, plan.out)
        if (args.executor or spec.executor) == "local":  # as the real run will, first
            from devlearn.sweep.executors import local_cores

            local_cores(spec.train.cores_per_run)
        print("\n".join(describe_plan(plan)))
        evaluations = sum(len(r.job.evaluations) for r in plan.runs)
        print(
            f"{len(plan.trained)} runs ({len(spec.arms)} arms x {len(spec.seeds)} seeds), "
            f"{len(spec.baselines)} baseline(s), {evaluations} evaluations in {plan.out}; "
            "nothing started (--dry-run)"
        )
        return 0
    with interrupt_at_once():
        return run_experiment(
            spec,
            args.out,
            registry,
            jobs=jobs,
            executor=args.executor,
            address=args.address,
            global_args=global_args,
            command=shlex.join(sys.argv),
        )


def _publish(args: argparse.Namespace, registry: PluginRegistry) -> int:
    from devlearn.experiment import publish_experiment

    publish_experiment(args.out, args.dest, registry, stream=sys.stdout)
    return 0


def _table(args: argparse.Namespace, registry: PluginRegistry) -> int:
    from devlearn.experiment import experiment_table, markdown
    from devlearn.files import check_out_file, write_text_atomically

    out = Path(args.out) if args.out else None
    if out is not None:  # a folder, a device or FIFO, an unwritable place: refused first
        check_out_file(out, parents=True)
    table = experiment_table(
        args.dest, args.metric or (), versus=args.versus, ignore_config=args.ignore_config or ()
    )
    text = json.dumps(table, indent=2) + "\n" if args.json else markdown(table)
    if out is not None:
        try:
            out.parent.mkdir(parents=True, exist_ok=True)
            write_text_atomically(out, text)
        except OSError as exc:
            raise UsageError(f"cannot write --out {out}: {exc.strerror or exc}") from None
    sys.stdout.write(text)
    return 0


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Run the action the command line names."""
    actions = {"run": _run, "publish": _publish, "table": _table}
    return actions[args.action](args, registry)
