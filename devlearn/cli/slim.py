"""``devlearn slim CHECKPOINT``: write a policy file (weights, config, calibration) for sharing."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Write the policy file and say where, and how much smaller it is."""
    from devlearn.evaluation.evaluate import POLICY_FILE, resolve_checkpoint
    from devlearn.evaluation.policy_file import slim_checkpoint
    from devlearn.files import check_out_file

    source = resolve_checkpoint(args.checkpoint)
    target = Path(args.out) if args.out else source.parent / POLICY_FILE
    check_out_file(target, parents=True)  # a device or FIFO, a folder: before the checkpoint
    state = slim_checkpoint(source, target, registry)
    size, before = target.stat().st_size, source.stat().st_size
    extras = ", ".join(state["artifacts"]) or "none"
    print(
        f"wrote {target} ({size / 1e6:.1f} MB, from {before / 1e6:.1f} MB; "
        f"{state['behavior']}, {state.get('env_steps', 0)} steps; artifacts: {extras})"
    )
    return 0
