"""The sweep folder: sweep.json (what the sweep is), runs.json (every run's record), the lock.

Layout::

    SWEEP/sweep.json          behaviour, grid, seeds, budget, evaluation; commands that ran it
    SWEEP/runs.json           every run's record (status, commands, wall time, commit, results)
    SWEEP/records/NAME.json   one run's record, written as the run goes
    SWEEP/logs/NAME.log       the output of every command of one run
    SWEEP/runs/NAME/          the run folder (devlearn run), its evaluation in eval/
    SWEEP/report/             devlearn report over the evaluated runs
"""

from __future__ import annotations

import datetime
from typing import Any

from devlearn.api.errors import UsageError
from devlearn.files import lock_exclusively
from devlearn.sweep.job import RunJob, read_json, write_json
from devlearn.sweep.spec import SweepSpec

SWEEP_FILE = "sweep.json"
RUNS_FILE = "runs.json"
LOCK_FILE = ".sweep.lock"


def _differences(old: Any, new: Any, prefix: str = "") -> list[str]:
    if isinstance(old, dict) and isinstance(new, dict):
        found = []
        for key in sorted(set(old) | set(new)):
            found += _differences(old.get(key), new.get(key), f"{prefix}{key}.")
        return found
    return [] if old == new else [f"{prefix[:-1]} was {old!r}, now {new!r}"]


def check_folder(spec: SweepSpec) -> dict[str, Any] | None:
    """Check that ``spec.out`` can hold this sweep, before anything is written.

    Returns:
        The folder's sweep.json when it holds this sweep already (a restart), else None.
    Raises:
        UsageError: A file; a folder holding something else; a sweep of another behaviour;
            the same sweep with a different budget or evaluation.
    """
    out = spec.out
    if out.exists() and not out.is_dir():
        raise UsageError(f"sweep folder {out} is a file")
    if not out.exists():
        return None
    saved = read_json(out / SWEEP_FILE)
    if saved is None:
        if any(out.iterdir()):
            raise UsageError(
                f"{out} is not a sweep folder (no readable {SWEEP_FILE}) and not empty; "
                "give a new or empty folder"
            )
        return None
    what = saved.get("what", {})
    if what.get("behavior") != spec.behavior:
        raise UsageError(
            f"sweep folder {out} holds a sweep of '{what.get('behavior')}', not "
            f"'{spec.behavior}'; give another --out"
        )
    changed = _differences(what, spec.what())
    if changed:
        raise UsageError(
            f"sweep folder {out} was started with other settings ({'; '.join(changed)}); "
            "restart it with the same ones, or give another --out"
        )
    return saved


class SweepFolder:
    """An open sweep folder, locked against a second sweep process for as long as it is open."""

    def __init__(self, spec: SweepSpec, saved: dict[str, Any] | None, command: str) -> None:
        self.path = spec.out
        self.path.mkdir(parents=True, exist_ok=True)
        self._lock = lock_exclusively(self.path / LOCK_FILE, f"sweep folder {self.path}")
        now = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
        info = saved or {"what": spec.what(), "created": now, "starts": []}
        info.update(
            grid=spec.grid,
            seeds=spec.seeds,
            executor=spec.executor,
            cores_per_run=spec.train.cores_per_run,
        )
        info.setdefault("starts", []).append({"time": now, "command": command})
        write_json(self.path / SWEEP_FILE, info)

    def finished_record(self, job: RunJob) -> dict[str, Any] | None:
        """The record of a run already done and evaluated (it is not run again), else None."""
        record = read_json(job.record_path)
        if (
            record
            and record.get("status") == "done"
            and (job.run_dir / "eval" / "eval.json").is_file()
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
        """Write runs.json: every run's record, in the sweep's order."""
        write_json(self.path / RUNS_FILE, {"runs": records})

    def close(self) -> None:
        """Release the lock."""
        self._lock.close()
