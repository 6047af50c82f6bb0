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


def _duration(seconds: float) -> str:
    """``45 s``, ``12 min``, ``3.4 h``."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


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
        self.started = time.monotonic()
        self.first_step: dict[str, int] = {}  # name -> its step when first seen by this start
        self.step: dict[str, int] = {}  # name -> its latest step seen
        self.ended: set[str] = set()  # runs that ended (done, failed, or earlier)

    def line(self, state: str, name: str, detail: str = "") -> None:
        """One line: state, run, detail."""
        text = f"{state:<11} {name}" + (f"  {detail}" if detail else "")
        tqdm.write(text, file=self.stream)
        self.shown[name] = (state, time.monotonic())
        if hasattr(self.stream, "flush"):
            self.stream.flush()

    def _result(self, record: dict[str, Any]) -> str:
        """Wall time and the headline, as ``devlearn eval``'s summary picks it (the per-episode
        mean where the evaluator reports one)."""
        from devlearn.evaluation.report import headline_of

        found = headline_of(record.get("eval") or {}, self.headline or "")
        values = [f"{found[0]}={_number(found[1])}"] if found else []
        return "  ".join([f"{record.get('wall_s', 0):.1f} s", *values])

    def earlier(self, record: dict[str, Any]) -> None:
        """A run finished by an earlier start of the sweep (not run again)."""
        self.line("done", record["name"], f"(earlier) {self._result(record)}")
        self.ended.add(record["name"])
        self.bar.update()

    def eta(self, totals: dict[str, int]) -> float | None:
        """Seconds until every run has trained, at the rate (steps per second, all runs
        together, evaluations' time included) of this start so far; None before a rate is
        known or when nothing is left to train."""
        trained = sum(self.step[n] - self.first_step[n] for n in self.step)
        left = sum(
            max(0, total - self.step.get(name, 0))
            for name, total in totals.items()
            if name not in self.ended
        )
        elapsed = time.monotonic() - self.started
        if trained <= 0 or left <= 0 or elapsed <= 0:
            return None
        return left / (trained / elapsed)

    def tick(self, jobs: list[RunJob], totals: dict[str, int]) -> None:
        """Look at the runs handed to the executor: print what changed; a training run's line
        (every ``interval`` s) gives its steps, speed and the estimated time left."""
        lines = []
        for job in jobs:
            record = read_json(job.record_path) or {}
            state = record.get("status")
            if state not in ("training", "evaluating"):
                state = "queued"
            row = last_metrics(job.run_dir) if state == "training" else None
            if row and isinstance(row.get("step"), int):
                self.first_step.setdefault(job.name, row["step"])
                self.step[job.name] = row["step"]
            before, when = self.shown.get(job.name, (None, 0.0))
            if state == "training":
                if state == before and time.monotonic() - when < self.interval:
                    continue
                detail = "starting" if job.trainer is None else "(its trainer reports no steps)"
                if row:
                    detail = f"{row.get('step', 0):,}/{totals[job.name]:,} steps"
                    if "steps_per_s" in row:
                        detail += f"  {row['steps_per_s']:.0f} steps/s"
                lines.append((state, job.name, detail))
            elif state != before:
                lines.append((state, job.name, ""))
        eta = self.eta(totals)
        for state, name, detail in lines:
            if state == "training" and eta is not None:
                detail += f"  ETA {_duration(eta)} (all training left)"
            self.line(state, name, detail)
        if eta is not None:
            failed = f", {self.failed} failed" if self.failed else ""
            self.bar.set_postfix_str(f"ETA {_duration(eta)}{failed}")

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
            self.ended.add(name)
            self.bar.update()
        if self.failed:
            self.bar.set_postfix(failed=self.failed)

    def close(self) -> None:
        """End the bar."""
        self.bar.close()
