"""``devlearn eval BEHAVIOR --checkpoint PATH``: run a trained policy and report its metrics."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from devlearn.errors import UsageError


def add_parser(subparsers) -> list[str]:
    """Register the ``eval`` sub-command."""
    p = subparsers.add_parser(
        "eval",
        help="evaluate a trained checkpoint",
        description="Run deterministic episodes (the policy's mean action) in the behaviour's "
        "evaluation stage; writes eval.json and the behaviour's pictures to --out.",
    )
    p.add_argument("behavior", help="behaviour name (see `devlearn plugins`)")
    p.add_argument("--checkpoint", required=True, metavar="PATH", help="checkpoint file (.pt)")
    p.add_argument("--episodes", default="10", metavar="N", help="episodes to run (default 10)")
    p.add_argument("--seed", default="0", metavar="S", help="seed of the initial poses")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.add_argument("--video", metavar="PATH", help="write an MP4 of the first episode")
    p.add_argument("--out", metavar="DIR", help="output directory (default CHECKPOINT_DIR/eval)")
    return ["eval"]


def _count(text: str, option: str, minimum: int) -> int:
    try:
        value = int(text)
    except ValueError:
        raise UsageError(f"{option} must be an integer, got '{text}'") from None
    if value < minimum:
        raise UsageError(f"{option} must be at least {minimum}, got {value}")
    return value


def run(args: argparse.Namespace, registry) -> int:
    """Evaluate and print the summary (a table, or JSON with --json)."""
    from devlearn.training.evaluate import evaluate

    registry.behavior(args.behavior)  # unknown behaviour: one clear line
    episodes = _count(args.episodes, "--episodes", 1)
    seed = _count(args.seed, "--seed", 0)
    checkpoint = Path(args.checkpoint)
    out_dir = Path(args.out) if args.out else checkpoint.parent / "eval"
    summary = evaluate(
        args.behavior, checkpoint, episodes, registry, video=args.video, seed=seed, out_dir=out_dir
    )
    if args.json:
        print(json.dumps(summary, indent=2, default=float))
        return 0
    width = max((len(k) for k in summary), default=0)
    for key, value in summary.items():
        text = f"{value:.4g}" if isinstance(value, float) else json.dumps(value, default=float)
        print(f"{key.ljust(width)}  {text}")
    print(f"written to {out_dir}" + (f"; video {args.video}" if args.video else ""))
    return 0
