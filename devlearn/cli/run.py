"""``devlearn run BEHAVIOR``: train a behaviour with PPO (or resume a run)."""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from devlearn.api.errors import UsageError

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Resolve the config, train, print the run directory and a final summary."""
    from devlearn.cli.summary import finished_message, paper_budget, run_summary
    from devlearn.config.resolve import RunRequest, resolve_run
    from devlearn.training.checkpoint import checkpoint_config
    from devlearn.training.train import default_run_dir, train

    behavior_cls = registry.behavior(args.behavior)
    if args.resume and args.force:
        raise UsageError("--force and --resume exclude each other (--force replaces a run)")
    from devlearn.training.run_folder import check_not_in_use

    # another run trains there: refused before any work (rank 0 alone locks a torchrun run's
    # folder, so the other ranks would find it in use by their own run)
    if int(os.environ.get("RANK", "0")) == 0:
        for folder in (args.resume, args.out):
            if folder:
                check_not_in_use(Path(folder))
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
    resolved = resolve_run(request, registry, checkpoint_config)  # the run trains its behaviour
    cfg = resolved.cfg
    for note in resolved.notes:
        print(f"devlearn: note: {note}", file=sys.stderr)
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
            resolved,
            registry,
            resume=args.resume,
            start_from=args.start_from,
            force=args.force,
            started=started,
        )
    budget = paper_budget(behavior_cls.about.presets)
    metric = behavior_cls.about.headline_metric
    summary = run_summary(
        result, cfg.behavior_name, metric, cfg.total_steps, cfg.num_envs, budget, cfg.behavior
    )
    print(summary)
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
