"""``devlearn run BEHAVIOR``: train a behaviour with PPO (or resume a run)."""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from devlearn.api.errors import UsageError
from devlearn.cli.options import add_behavior, add_overrides, add_preset

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry


def add_parser(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> list[str]:
    """Register the ``run`` sub-command."""
    p = subparsers.add_parser(
        "run",
        help="train a behaviour with PPO",
        description="Train a behaviour; writes config.json, checkpoints, metrics.jsonl and "
        "TensorBoard logs to the run directory. Ctrl-C or SIGTERM saves a checkpoint; "
        "--resume continues.",
    )
    add_behavior(p)
    p.add_argument("--steps", metavar="N", help="total environment steps (e.g. 8e6)")
    p.add_argument("--envs", metavar="N", help="environments per process")
    p.add_argument(
        "--workers",
        metavar="N",
        help="environment worker processes (0: in process; default -1: one per core)",
    )
    p.add_argument("--seed", metavar="S", help="random seed")
    p.add_argument("--out", metavar="DIR", help="run directory (default runs/BEHAVIOR-TIME)")
    p.add_argument("--device", metavar="DEV", help="cpu or cuda (default cpu)")
    p.add_argument(
        "--logger", choices=("tensorboard", "wandb"), help="also log to W&B (default tensorboard)"
    )
    add_overrides(p)
    add_preset(p)
    p.add_argument("--resume", metavar="RUN_DIR", help="continue a run from its latest checkpoint")
    p.add_argument(
        "--from",
        dest="start_from",
        metavar="CHECKPOINT",
        help="start a new run (in --out) from another run's checkpoint: its config (changed by "
        "--set and the options above), weights, optimiser, step count and env memory",
    )
    p.add_argument(
        "--config",
        metavar="FILE",
        help="start a new run from a resolved config file (a run's config.json, a sweep's "
        "run_config.json), changed by --set and the options above",
    )
    p.add_argument(
        "--force",
        action="store_true",
        help="with --out: replace the run that DIR holds (deletes what DIR holds once the new "
        "run has started); without it such a folder is refused",
    )
    return ["run"]


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Resolve the config, train, print the run directory and a final summary."""
    from devlearn.cli.summary import finished_message, paper_budget, run_summary
    from devlearn.config.resolve import RunRequest, resolve_config
    from devlearn.training.checkpoint import checkpoint_config
    from devlearn.training.train import default_run_dir, train

    behavior_cls = registry.behavior(args.behavior)
    if args.resume and args.force:
        raise UsageError("--force and --resume exclude each other (--force replaces a run)")
    request = RunRequest(
        behavior=args.behavior,
        overrides=args.overrides,
        preset=args.preset or "",
        top={
            "total_steps": args.steps,
            "num_envs": args.envs,
            "workers": args.workers,
            "seed": args.seed,
            "device": args.device,
            "logger": args.logger,
        },
        out_dir=args.out or "",
        resume=args.resume or "",
        start_from=args.start_from or "",
        config_file=args.config or "",
    )
    cfg = resolve_config(request, registry, checkpoint_config)
    if not args.resume and not cfg.out_dir:
        cfg.out_dir = str(default_run_dir(cfg.behavior_name))
    if args.resume:
        from devlearn.training.checkpoint import resume_checkpoint

        skipped: list[str] = []
        found = resume_checkpoint(args.resume, skipped)
        for note in skipped:  # an unreadable newer checkpoint: say which one is used instead
            print(f"devlearn: warning: {note}", file=sys.stderr)
        if message := finished_message(args.resume, cfg, found):
            print(message)
            return 0

    def started(run_dir: Path) -> None:  # once the run is built
        print(f"run directory: {run_dir}", flush=True)

    # SIGTERM (cluster schedulers, ``kill``) acts as Ctrl-C: a checkpoint is saved at the next
    # decision, never inside a compiled kernel (StopRequests); Ctrl-C works even where the
    # shell started us with it ignored (``cmd &`` in a script)
    from devlearn.training.process import StopRequests

    with StopRequests.installed():
        result = train(
            cfg,
            registry,
            resume=args.resume,
            start_from=args.start_from,
            force=args.force,
            started=started,
        )
    budget = paper_budget(behavior_cls(cfg.behavior).presets())
    metric = behavior_cls.headline_metric
    print(run_summary(result, cfg.behavior_name, metric, cfg.total_steps, cfg.num_envs, budget))
    return 0


@contextlib.contextmanager
def interrupt_at_once() -> Iterator[None]:
    """Within the block, SIGTERM acts as Ctrl-C at once (``KeyboardInterrupt`` wherever it
    lands), and Ctrl-C works even where the shell started us with it ignored: for a process
    that runs no compiled kernel of its own (a sweep, which waits on its runs)."""

    def interrupt(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    try:
        before = {
            s: signal.signal(s, h)
            for s, h in ((signal.SIGTERM, interrupt), (signal.SIGINT, signal.default_int_handler))
        }
    except ValueError:  # not the main thread (an embedding program): leave its handlers
        before = {}
    try:
        yield
    finally:
        for signum, handler in before.items():
            signal.signal(signum, handler)
