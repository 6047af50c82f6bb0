"""``devlearn eval BEHAVIOR --checkpoint PATH | --policy zero|random|held_random``: evaluate."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from devlearn.api.errors import UsageError
from devlearn.cli.folders import removed_on_failure

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry


def add_parser(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> list[str]:
    """Register the ``eval`` sub-command."""
    p = subparsers.add_parser(
        "eval",
        help="evaluate a trained checkpoint or a baseline policy",
        description="Run episodes in the behaviour's evaluation stage (a checkpoint's mean "
        "action, or a zero / uniform-random / held-random baseline under the same protocol); "
        "writes "
        "eval.json (with the protocol) and the behaviour's pictures to --out.",
    )
    p.add_argument("behavior", help="behaviour name (see `devlearn plugins`)")
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument(
        "--checkpoint",
        metavar="PATH",
        help="checkpoint or policy file (.pt), or a run folder (its checkpoint_latest.pt)",
    )
    source.add_argument(
        "--policy",
        choices=("zero", "random", "held_random"),
        help="baseline instead of a checkpoint: zero action, uniform random in [-1, 1] every "
        "step, or held_random (uniform random actions held ~8 steps, as babbling)",
    )
    p.add_argument("--episodes", default="10", metavar="N", help="episodes to run (default 10)")
    p.add_argument("--seed", default="0", metavar="S", help="seed of the initial poses")
    p.add_argument(
        "--start",
        choices=("stage", "babybench", "rest", "random"),
        default="stage",
        help="where episodes start: stage (default): the behaviour's evaluation protocol "
        "(self_touch: seeded random poses; hand_regard: babybench), or for a behaviour that "
        "declares none, the curriculum stage where the policy trained; babybench (the scene's "
        "settled state + 10 seeded random-action steps, as BabyBench's reset); rest (that "
        "state alone, every episode: a deterministic policy then repeats one episode); "
        "random (random joint angles: generalisation)",
    )
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        dest="overrides",
        help="a baseline's config value, e.g. behavior.detector_file=runs/hr/hand_detector.json "
        "(hand regard's baselines then score with a calibrated detector); repeatable",
    )
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.add_argument("--video", metavar="PATH", help="write an MP4 of the first episode")
    p.add_argument(
        "--out",
        metavar="DIR",
        help="output directory (default CHECKPOINT_DIR/eval; baselines: eval_BEHAVIOR_POLICY)",
    )
    return ["eval"]


EPISODES_MAX = 1_000_000
"""Largest ``--episodes``."""


def _count(text: str, option: str, minimum: int, maximum: int) -> int:
    try:
        value = int(text)
    except ValueError:
        raise UsageError(f"{option} must be an integer, got '{text}'") from None
    if value < minimum:
        raise UsageError(f"{option} must be at least {minimum}, got {value}")
    if value > maximum:
        raise UsageError(f"{option} must be at most {maximum}, got {value}")
    return value


def _print(summary: dict, as_json: bool) -> None:
    if as_json:
        print(json.dumps(summary, indent=2, default=float))
        return
    shown = {k: v for k, v in summary.items() if k not in ("config", "part_touch_steps")}
    width = max((len(k) for k in shown), default=0)
    for key, value in shown.items():
        text = f"{value:.4g}" if isinstance(value, float) else json.dumps(value, default=float)
        print(f"{key.ljust(width)}  {text}")


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Evaluate and print the summary (a table, or JSON with --json), then where files went.

    The summary is printed even when writing the files failed (then exit code 2).
    """
    from devlearn.evaluation.evaluate import EvalWriteError, evaluate, resolve_checkpoint

    registry.behavior(args.behavior)  # unknown behaviour: one clear line
    from devlearn.config.checks import SEED_MAX

    episodes = _count(args.episodes, "--episodes", 1, EPISODES_MAX)
    seed = _count(args.seed, "--seed", 0, SEED_MAX)
    checkpoint = resolve_checkpoint(args.checkpoint) if args.checkpoint else None
    if args.out:
        out_dir = Path(args.out)
    elif checkpoint is not None:
        out_dir = checkpoint.parent / "eval"
    else:
        out_dir = Path(f"eval_{args.behavior}_{args.policy}")
    try:
        with removed_on_failure(out_dir):
            summary = evaluate(
                args.behavior,
                checkpoint,
                episodes,
                registry,
                video=args.video,
                seed=seed,
                out_dir=out_dir,
                policy=args.policy or "checkpoint",
                start=args.start,
                overrides=args.overrides,
            )
    except EvalWriteError as exc:
        _print(exc.summary, args.json)
        raise
    written = summary.pop("written", [])
    _print(summary, args.json)
    files = ", ".join(Path(p).name for p in written)
    # stderr with --json, so that stdout stays one JSON document
    print(
        f"written to {out_dir}: {files}" + (f"; video {args.video}" if args.video else ""),
        file=sys.stderr if args.json else sys.stdout,
    )
    return 0
