"""``devlearn plugins``: list installed plugins and what each registered; enable or disable."""

from __future__ import annotations

import argparse
import json

from devlearn.api.errors import UsageError
from devlearn.plugins import PluginRegistry, set_plugin_disabled


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """List plugins as a table or JSON, or change which are disabled."""
    for name, disable in ((args.disable, True), (args.enable, False)):
        if name:
            if name not in registry.plugins:
                valid = ", ".join(sorted(registry.plugins)) or "none"
                raise UsageError(f"unknown plugin '{name}'; installed: {valid}")
            path = set_plugin_disabled(name, disable)
            print(f"plugin '{name}' {'disabled' if disable else 'enabled'} (saved in {path})")
            return 0
    infos = list(registry.plugins.values())
    if args.json:
        print(json.dumps([info.to_json() for info in infos], indent=2))
        return 0
    if not infos:
        print("no devlearn plugins installed")
        return 0
    rows = [("plugin", "distribution", "version", "behaviors", "hooks", "status")]
    for info in infos:
        status = "disabled" if info.disabled else ("BROKEN: " + info.error if info.error else "ok")
        rows.append(
            (
                info.name,
                info.distribution,
                info.version,
                ", ".join(info.behaviors) or "-",
                ", ".join(info.hooks) or "-",
                status,
            )
        )
    widths = [max(len(r[i]) for r in rows) for i in range(5)]
    for row in rows:
        print("  ".join(c.ljust(w) for c, w in zip(row[:5], widths)) + "  " + row[5])
    return 0
