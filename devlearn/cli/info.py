"""``devlearn info BEHAVIOR``: what a behaviour's environment looks like."""

from __future__ import annotations

import argparse
import json
from typing import TYPE_CHECKING

from devlearn.evaluation.describe import describe_behavior

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Print the description as a table or JSON."""
    from devlearn.config.resolve import RunRequest, resolve_config

    cfg = resolve_config(RunRequest(args.behavior), registry)  # what `devlearn run` would use
    behavior = registry.create(args.behavior, cfg.behavior)
    info = describe_behavior(behavior, action_repeat=cfg.env.action_repeat)
    info["plugin"] = registry.plugin_of(args.behavior).name
    if args.json:
        print(json.dumps(info, indent=2))
        return 0
    width = max(len(k) for k in info)
    for key, value in info.items():
        if key == "observations":
            shapes = ", ".join(f"{name} {tuple(shape)}" for name, shape in value.items())
            print(f"{key.ljust(width)}  {shapes}")
        elif key == "curriculum":
            stages = " -> ".join(f"{s['name']} ({s['steps'] or 'rest'})" for s in value)
            print(f"{key.ljust(width)}  {stages}")
        elif isinstance(value, (list, dict)):
            print(f"{key.ljust(width)}  {json.dumps(value)}")
        else:
            print(f"{key.ljust(width)}  {value}")
    return 0
