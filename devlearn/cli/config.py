"""``devlearn config BEHAVIOR``: every config key of a run, with type, default and docstring."""

from __future__ import annotations

import argparse
import json
import textwrap
from typing import TYPE_CHECKING

from devlearn.config.help import describe_keys
from devlearn.config.resolve import RunRequest, resolve_config
from devlearn.config.run_config import new_config

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Print the keys as a table (grouped by section) or as JSON.

    The values shown are resolved and checked as ``devlearn run`` resolves and checks them
    (:func:`~devlearn.config.resolve.resolve_config`): a value ``run`` refuses is refused here
    with the same line. Each key is marked by what set it: the behaviour, the preset, ``--set``.
    """
    behavior_cls = registry.behavior(args.behavior)
    core = new_config(behavior_cls)
    # the behaviour's defaults, then --preset, then --set: each resolved, so a mark names
    # what changed a value
    steps = [("", RunRequest(args.behavior))]
    if args.preset:
        steps.append(("preset", RunRequest(args.behavior, preset=args.preset)))
    if args.overrides:
        steps.append(("override", RunRequest(args.behavior, args.overrides, args.preset or "")))
    rows: list[dict] = []
    for label, request in steps:
        cfg = resolve_config(request, registry)
        marks = {r["key"]: (r["default"], r["set_by"]) for r in rows}
        rows = describe_keys(cfg, core)
        for row in rows if marks else ():
            value, mark = marks.get(row["key"], (None, label))  # a key --set added: its own
            row["set_by"] = label if row["default"] != value else mark
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    print(f"config keys of `devlearn run {behavior_cls.name}` (override with --set KEY=VALUE)")
    presets = behavior_cls.about.presets
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
