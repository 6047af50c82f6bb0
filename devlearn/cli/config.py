"""``devlearn config BEHAVIOR``: every config key of a run, with type, default and docstring."""

from __future__ import annotations

import argparse
import json
import textwrap

from devlearn.training.config import RunConfig, apply_overrides, default_config
from devlearn.training.config_help import describe_keys


def add_parser(subparsers) -> list[str]:
    """Register the ``config`` sub-command."""
    p = subparsers.add_parser(
        "config",
        help="list a behaviour's config keys (type, default, meaning)",
        description="List every key `devlearn run BEHAVIOR --set KEY=VALUE` accepts: the run's, "
        "PPO's and the behaviour's own, with type, the value a run would use and its docstring. "
        "Values set by the behaviour's train_defaults() are marked.",
    )
    p.add_argument("behavior", help="behaviour name (see `devlearn plugins`)")
    p.add_argument("--json", action="store_true", help="print a JSON list of keys")
    p.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="show the values after these overrides (checked as `devlearn run` would)",
    )
    return ["config"]


def run(args: argparse.Namespace, registry) -> int:
    """Print the keys as a table (grouped by section) or as JSON."""
    behavior_cls = registry.behavior(args.behavior)
    core = RunConfig(behavior_name=behavior_cls.name, behavior=behavior_cls.config_class())
    cfg = default_config(behavior_cls)
    rows = describe_keys(cfg, core)
    if args.overrides:
        before = {r["key"]: r["default"] for r in rows}
        rows = describe_keys(apply_overrides(cfg, args.overrides), core)
        for row in rows:
            if row["default"] != before[row["key"]]:
                row["set_by"] = "override"
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    print(f"config keys of `devlearn run {behavior_cls.name}` (override with --set KEY=VALUE)")
    section = None
    for row in rows:
        head = row["key"].split(".", 1)[0] if "." in row["key"] else "run"
        if head != section:
            section = head
            print(f"\n[{section}]")
        mark = {"behavior": "  (set by the behaviour)", "override": "  (--set)"}
        print(
            f"  {row['key']}: {row['type']} = {json.dumps(row['default'])}"
            f"{mark.get(row.get('set_by', ''), '')}"
        )
        if row["doc"]:
            print(
                textwrap.fill(row["doc"], 96, initial_indent="      ", subsequent_indent="      ")
            )
    return 0
