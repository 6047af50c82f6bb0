"""A sweep's progress: one line per run as its state changes, and an overall bar."""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Any, TextIO

from tqdm import tqdm

from devlearn.api.errors import UsageError
from devlearn.api.json_files import parse_json
from devlearn.sweep.job import RunJob, read_json

TRAINING_LINE_S = 30.0
"""Seconds between two progress lines of the same training run."""


def last_metrics(run_dir: Path) -> dict[str, Any] | None:
    """The last complete row of a run's metrics.jsonl (None before its first iteration)."""
    try:
        with open(run_dir / "metrics.jsonl", "rb") as f:
            f.seek(max(f.seek(0, 2) - 8192, 0))
            lines = f.read().decode(errors="replace").splitlines()
    except OSError:
        return None
    for line in reversed(lines):
        try:
            row = parse_json(line, "a metrics row")
        except UsageError:  # a line being written
            continue
        if isinstance(row, dict):
            return row
    return None


def _number(value: Any) -> str:
    return f"{value:.4g}" if isinstance(value, float) else str(value)


class Progress:
    """Prints run lines (stdout) and keeps a bar of finished runs (stderr, on a terminal)."""

    def __init__(
        self,
        total: int,
        headline: str | None,
        stream: TextIO | None = None,
        interval: float = TRAINING_LINE_S,
    ) -> None:
        self.stream = stream or sys.stdout
        self.headline = headline
        self.interval = interval
        self.bar = tqdm(total=total, unit="run", desc="sweep", file=sys.stderr, disable=None)
        self.shown: dict[str, tuple[str, float]] = {}  # name -> (state, when printed)
        self.failed = 0

    def line(self, state: str, name: str, detail: str = "") -> None:
        """One line: state, run, detail."""
        text = f"{state:<11} {name}" + (f"  {detail}" if detail else "")
        tqdm.write(text, file=self.stream)
        self.shown[name] = (state, time.monotonic())
        if hasattr(self.stream, "flush"):
            self.stream.flush()

    def _result(self, record: dict[str, Any]) -> str:
        summary = record.get("eval") or {}
        shown = [self.headline] if self.headline in summary else []
        values = [f"{k}={_number(summary[k])}" for k in shown]
        return "  ".join([f"{record.get('wall_s', 0):.1f} s", *values])

    def earlier(self, record: dict[str, Any]) -> None:
        """A run finished by an earlier start of the sweep (not run again)."""
        self.line("done", record["name"], f"(earlier) {self._result(record)}")
        self.bar.update()

    def tick(self, jobs: list[RunJob], totals: dict[str, int]) -> None:
        """Look at the runs handed to the executor: print what changed."""
        for job in jobs:
            record = read_json(job.record_path) or {}
            state = record.get("status")
            if state not in ("training", "evaluating"):
                state = "queued"
            before, when = self.shown.get(job.name, (None, 0.0))
            if state == "training":
                row = last_metrics(job.run_dir)
                if state == before and time.monotonic() - when < self.interval:
                    continue
                detail = "starting"
                if row:
                    detail = f"{row.get('step', 0):,}/{totals[job.name]:,} steps"
                    if "steps_per_s" in row:
                        detail += f"  {row['steps_per_s']:.0f} steps/s"
                self.line(state, job.name, detail)
            elif state != before:
                self.line(state, job.name)

    def finished(self, record: dict[str, Any], sweep_dir: Path) -> None:
        """A run ended: done, failed (with its log's last lines) or interrupted."""
        status, name = record.get("status"), record["name"]
        if status == "done":
            self.line("done", name, self._result(record))
        elif status == "interrupted":
            self.line("interrupted", name, "(continues from its checkpoint when restarted)")
        else:
            self.failed += 1
            log = sweep_dir / record.get("log", f"logs/{name}.log")
            self.line("failed", name, f"{record.get('error')} (log: {log})")
            for text in record.get("log_tail") or []:
                tqdm.write(f"    | {text}", file=self.stream)
        if status != "interrupted":
            self.bar.update()
        if self.failed:
            self.bar.set_postfix(failed=self.failed)

    def close(self) -> None:
        """End the bar."""
        self.bar.close()
