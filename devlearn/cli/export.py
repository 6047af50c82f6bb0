"""``devlearn export BEHAVIOR --checkpoint P --format onnx|torchscript --out FILE``."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from devlearn.cli.options import add_behavior

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry


def add_parser(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> list[str]:
    """Register the ``export`` sub-command."""
    p = subparsers.add_parser(
        "export",
        help="write a trained policy as ONNX or TorchScript",
        description="Write the deterministic policy (observations to the mean action, in "
        "[-1, 1]) of a checkpoint for use outside devlearn, e.g. on a robot. Inputs are the "
        "behaviour's observations by name, batch first, in the dtypes it observes (uint8 "
        "images, float32 otherwise); normalisation happens inside. ONNX needs the optional "
        "packages: pip install 'devlearn[export]'.",
    )
    add_behavior(p)
    p.add_argument("--checkpoint", required=True, metavar="PATH", help="checkpoint file (.pt)")
    p.add_argument("--format", default="onnx", metavar="FORMAT", help="onnx or torchscript")
    p.add_argument("--out", required=True, metavar="FILE", help="file to write")
    return ["export"]


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Export and print what was written and its inputs."""
    from devlearn.api.errors import UsageError
    from devlearn.evaluation.export import FORMATS, check_out_file, export_policy, load_policy

    if args.format not in FORMATS:
        raise UsageError(f"unknown export format '{args.format}'; valid: {', '.join(FORMATS)}")
    from devlearn.cli.folders import removed_on_failure

    registry.behavior(args.behavior)  # unknown behaviour: one clear line
    check_out_file(Path(args.out))  # before the checkpoint and its environment are built
    policy, obs = load_policy(args.behavior, Path(args.checkpoint), registry)
    with removed_on_failure(args.out):  # an empty file the exporter opened first
        out = export_policy(policy, obs, args.format, Path(args.out))
    inputs = ", ".join(f"{n} {tuple(obs[n].shape)} {obs[n].dtype}" for n in policy.names)
    print(f"wrote {out} ({args.format}); inputs (batch first): {inputs}; output: action")
    return 0
