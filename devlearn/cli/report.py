"""``devlearn report PATH...``: a table and a chart of evaluations, variants beside baselines."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry


def add_parser(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> list[str]:
    """Register the ``report`` sub-command."""
    p = subparsers.add_parser(
        "report",
        help="table and chart of evaluations: mean and 95%% interval over seeds",
        description="Read evaluation folders (eval.json) or run folders containing them, group "
        "them by variant (the config keys that differ; seeds pooled) and write report.md (mean "
        "and 95%% t-interval over seeds per metric, zero/random baselines beside them when "
        "given or found next to the paths, and the paper's figures where the behaviour "
        "gives them) and report.png.",
    )
    p.add_argument("paths", nargs="+", metavar="PATH", help="evaluation or run folders")
    p.add_argument("--out", default="report", metavar="DIR", help="output folder (default report)")
    return ["report"]


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Write the report and print its table."""
    from pathlib import Path

    from devlearn.evaluation.report import write_report

    def paper_results(behavior: str, config: dict) -> tuple[str, dict[str, float]] | None:
        if behavior not in registry.behaviors():
            return None  # its plugin is not installed: no paper column
        return registry.behavior(behavior).paper_results(config)

    def as_loaded(behavior: str, config: dict) -> dict:
        from devlearn.api.errors import UsageError
        from devlearn.config.run_config import from_dict, to_dict

        if behavior not in registry.behaviors():
            return config  # its plugin is not installed: compared as saved
        try:
            return to_dict(from_dict(config, registry.behavior(behavior)))
        except UsageError:
            return config  # a config this version cannot read: compared as saved

    from devlearn.cli.folders import removed_on_failure

    with removed_on_failure(args.out):
        write_report(args.paths, args.out, paper_results, as_loaded)
    print((Path(args.out) / "report.md").read_text(), end="")
    print(f"written to {args.out}: report.md, report.png")
    return 0
