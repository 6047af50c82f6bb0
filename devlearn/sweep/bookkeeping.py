"""The sweep folder: sweep.json (what the sweep is), runs.json (every run's record), the lock.

Layout::

    SWEEP/sweep.json          behaviour, grid, seeds, budget, evaluation; commands that ran it
    SWEEP/runs.json           every run's record (status, commands, wall time, commit, results)
    SWEEP/records/NAME.json   one run's record, written as the run goes
    SWEEP/logs/NAME.log       the output of every command of one run
    SWEEP/runs/NAME/          the run folder (devlearn run), its evaluation in eval/
    SWEEP/report/             devlearn report over the evaluated runs

An experiment's folder (:mod:`devlearn.experiment`) is kept the same way (:class:`RunFolder`),
with experiment.json in place of sweep.json.
"""

from __future__ import annotations

import datetime
from pathlib import Path
from typing import Any

from devlearn.api.errors import UsageError
from devlearn.files import lock_exclusively
from devlearn.sweep.job import RunJob, read_json, write_json
from devlearn.sweep.spec import SweepSpec

SWEEP_FILE = "sweep.json"
RUNS_FILE = "runs.json"
LOCK_FILE = ".sweep.lock"


def differences(old: Any, new: Any, prefix: str = "") -> list[str]:
    """Every leaf that differs between two nested dicts: ``a.b was 1, now 2``."""
    if isinstance(old, dict) and isinstance(new, dict):
        found = []
        for key in sorted(set(old) | set(new)):
            found += differences(old.get(key), new.get(key), f"{prefix}{key}.")
        return found
    return [] if old == new else [f"{prefix[:-1]} was {old!r}, now {new!r}"]


def saved_info(out: Path, info_file: str, kind: str) -> dict[str, Any] | None:
    """What a folder to hold a sweep or experiment holds already, before anything is written.

    Returns:
        Its ``info_file`` (sweep.json, experiment.json) when there is one, else None (a new or
        empty folder).
    Raises:
        UsageError: A file, or a folder that holds something else.
    """
    if out.exists() and not out.is_dir():
        raise UsageError(f"{kind} folder {out} is a file")
    if not out.exists():
        return None
    saved = read_json(out / info_file)
    if saved is None and any(out.iterdir()):
        raise UsageError(
            f"{out} is not a {kind} folder (no readable {info_file}) and not empty; "
            "give a new or empty folder"
        )
    return saved


def check_folder(spec: SweepSpec) -> dict[str, Any] | None:
    """Check that ``spec.out`` can hold this sweep, before anything is written.

    Returns:
        The folder's sweep.json when it holds this sweep already (a restart), else None.
    Raises:
        UsageError: A file; a folder holding something else; a sweep of another behaviour;
            the same sweep with a different budget or evaluation.
    """
    out = spec.out
    saved = saved_info(out, SWEEP_FILE, "sweep")
    if saved is None:
        return None
    what = saved.get("what", {})
    if what.get("behavior") != spec.behavior:
        raise UsageError(
            f"sweep folder {out} holds a sweep of '{what.get('behavior')}', not "
            f"'{spec.behavior}'; give another --out"
        )
    changed = differences(what, spec.what())
    if changed:
        raise UsageError(
            f"sweep folder {out} was started with other settings ({'; '.join(changed)}); "
            "restart it with the same ones, or give another --out"
        )
    return saved


class RunFolder:
    """A folder of runs (a sweep's, an experiment's), locked against a second process for as
    long as it is open: its info file, every run's record, runs.json."""

    def __init__(self, path: Path, kind: str, info_file: str, info: dict[str, Any]) -> None:
        self.path = path
        self.path.mkdir(parents=True, exist_ok=True)
        self._lock = lock_exclusively(self.path / LOCK_FILE, f"{kind} folder {self.path}")
        write_json(self.path / info_file, info)

    def finished_record(self, job: RunJob) -> dict[str, Any] | None:
        """The record of a run already done and evaluated (it is not run again), else None."""
        record = read_json(job.record_path)
        if (
            record
            and record.get("status") == "done"
            and all((job.run_dir / f / "eval.json").is_file() for f in job.evaluations)
        ):
            return record
        return None

    def mark_queued(self, job: RunJob) -> None:
        """A run about to be handed to the executor: its record (if any) says queued, not the
        state an earlier, killed sweep left it in."""
        record = read_json(job.record_path)
        if record is not None and record.get("status") != "queued":
            record["status"] = "queued"
            write_json(job.record_path, record)

    def write_runs(self, records: list[dict[str, Any]]) -> None:
        """Write runs.json: every run's record, in the folder's order."""
        write_json(self.path / RUNS_FILE, {"runs": records})

    def close(self) -> None:
        """Release the lock."""
        self._lock.close()


def now() -> str:
    """The time, UTC, to the second (ISO 8601)."""
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")


class SweepFolder(RunFolder):
    """An open sweep folder: sweep.json (what the sweep is, every start's command) and the
    runs' records."""

    def __init__(self, spec: SweepSpec, saved: dict[str, Any] | None, command: str) -> None:
        info = saved or {"what": spec.what(), "created": now(), "starts": []}
        info.update(
            grid=spec.grid,
            seeds=spec.seeds,
            executor=spec.executor,
            cores_per_run=spec.train.cores_per_run,
        )
        info.setdefault("starts", []).append({"time": now(), "command": command})
        super().__init__(spec.out, "sweep", SWEEP_FILE, info)
