"""``devlearn config BEHAVIOR``: every config key of a run, with type, default and docstring."""

from __future__ import annotations

import argparse
import json
import textwrap
from typing import TYPE_CHECKING

from devlearn.config.checks import check_config
from devlearn.config.help import describe_keys
from devlearn.config.run_config import apply_preset, default_config, new_config
from devlearn.config.values import apply_overrides

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Print the keys as a table (grouped by section) or as JSON."""
    behavior_cls = registry.behavior(args.behavior)
    core = new_config(behavior_cls)
    cfg = default_config(behavior_cls)
    rows = describe_keys(cfg, core)
    changes = [("preset", lambda c: apply_preset(c, behavior_cls, args.preset), args.preset)]
    changes.append(("override", lambda c: apply_overrides(c, args.overrides), args.overrides))
    for label, change, wanted in changes:  # mark what --preset, then --set changed
        if wanted:
            marks = {r["key"]: (r["default"], r["set_by"]) for r in rows}
            cfg = change(cfg)
            check_config(cfg)  # as `devlearn run` checks it, before describing it
            rows = describe_keys(cfg, core)
            for row in rows:
                value, mark = marks[row["key"]]
                row["set_by"] = label if row["default"] != value else mark
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    print(f"config keys of `devlearn run {behavior_cls.name}` (override with --set KEY=VALUE)")
    presets = behavior_cls(cfg.behavior).presets()
    for name, values in presets.items():
        shown = ", ".join(f"{k}={json.dumps(v)}" for k, v in values.items())
        print(f"preset {name} (--preset {name}): {shown}")

    def head(row: dict) -> str:
        return row["key"].split(".", 1)[0] if "." in row["key"] else "run"

    order: dict[str, int] = {}
    for row in rows:
        order.setdefault(head(row), len(order))
    # one block per section, in order of first appearance (the run's own keys come both
    # before and after the nested sections in the dataclass)
    rows = sorted(rows, key=lambda row: order[head(row)])
    section = None
    for row in rows:
        head_name = head(row)
        if head_name != section:
            section = head_name
            print(f"\n[{section}]")
        mark = {
            "behavior": "  (set by the behaviour)",
            "override": "  (--set)",
            "preset": f"  (preset {args.preset})",
        }
        print(
            f"  {row['key']}: {row['type']} = {json.dumps(row['default'])}"
            f"{mark.get(row.get('set_by', ''), '')}"
        )
        if row["doc"]:
            print(
                textwrap.fill(row["doc"], 96, initial_indent="      ", subsequent_indent="      ")
            )
    return 0
