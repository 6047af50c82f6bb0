"""``devlearn export BEHAVIOR --checkpoint P --format onnx|torchscript --out FILE``."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Export and print what was written and its inputs."""
    from devlearn.api.errors import UsageError
    from devlearn.evaluation.export import FORMATS, export_policy, load_policy
    from devlearn.files import check_out_file

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
