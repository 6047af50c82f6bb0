"""``devlearn report PATH...``: a table and a chart of evaluations, variants beside baselines."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from pathlib import Path

    from devlearn.plugins import PluginRegistry


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Write the report and print its table."""
    from pathlib import Path

    from devlearn.evaluation.report import write_report

    def paper_results(behavior: str, config: dict) -> tuple[str, dict[str, float]] | None:
        if behavior not in registry.behaviors():
            return None  # its plugin is not installed: no paper column
        return registry.behavior(behavior).about.paper_figures(config)

    def as_loaded(behavior: str, config: dict) -> dict:
        from devlearn.api.errors import UsageError
        from devlearn.config.run_config import from_dict, to_dict

        if behavior not in registry.behaviors():
            return config  # its plugin is not installed: compared as saved
        try:
            return to_dict(from_dict(config, registry.behavior(behavior)))
        except UsageError:
            return config  # a config this version cannot read: compared as saved

    import sys

    from devlearn.cli.folders import removed_on_failure

    def headline(behavior: str) -> str:
        if behavior not in registry.behaviors():
            return ""  # its plugin is not installed: the protocol's headline alone
        return registry.behavior(behavior).about.headline_metric

    skipped: list[str] = []
    with removed_on_failure(args.out):
        write_report(args.paths, args.out, paper_results, as_loaded, skipped, headline)
    for reason in skipped:  # a stray file beside the evaluations: left out, said so
        print(f"devlearn: warning: left out an evaluation beside them: {reason}", file=sys.stderr)
    text = (Path(args.out) / "report.md").read_text()
    print(text if args.full else shortened(text, Path(args.out) / "report.md"), end="")
    print(f"written to {args.out}: report.md, report.png")
    return 0


def shortened(report: str, where: Path) -> str:
    """``report`` with its metric table cut to the first rows (the headline leads), and a line
    saying how many more rows ``where`` holds: an evaluation records hundreds of figures (the
    coded touches per limb and area), which would scroll the headline off a terminal."""
    from devlearn.cli.commands import REPORT_ROWS_SHOWN

    lines = report.splitlines(keepends=True)
    rows = [i for i, line in enumerate(lines) if line.startswith("| `")]
    if len(rows) <= REPORT_ROWS_SHOWN:
        return report
    cut, last = rows[REPORT_ROWS_SHOWN], rows[-1]
    more = len(rows) - REPORT_ROWS_SHOWN
    note = f"\n({more} more metrics in {where}; `devlearn report ... --full` prints them)\n"
    return "".join([*lines[:cut], note, *lines[last + 1 :]])
