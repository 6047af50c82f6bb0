"""Where a sweep's runs execute: this machine (``local``) or a Ray cluster (``ray``).

Both run :func:`devlearn.sweep.job.execute_job` per run and hand back its record the same way:
``submit(job)``, then ``wait(timeout)`` returns the records of runs that ended.
"""

from __future__ import annotations

import concurrent.futures
import queue
import socket
import threading
from typing import Any

from devlearn.api.errors import UsageError
from devlearn.cores import available_cores
from devlearn.sweep.job import STOP_TIMEOUT_S, RunJob, execute_job, read_json


def _failed(job: RunJob, error: str) -> dict[str, Any]:
    """The run's record from disk (what its job got to), marked failed with ``error``."""
    record = read_json(job.record_path) or {"name": job.name, "values": job.values}
    record.update(status="failed", error=error, log_tail=record.get("log_tail") or [])
    return record


def local_cores(cores_per_run: int) -> list[int]:
    """The cores this machine gives the sweep, if one run's ``cores_per_run`` fit in them.

    Raises:
        UsageError: A run needs more cores than the machine gives.
    """
    cores = available_cores()
    if cores_per_run > len(cores):
        raise UsageError(
            f"each run needs {cores_per_run} cores but this machine gives {len(cores)}; "
            "use fewer --workers or --cores"
        )
    return cores


class LocalExecutor:
    """Runs on this machine, ``jobs`` at a time, each pinned to its own ``cores_per_run`` cores.

    A 2-core machine runs two single-core runs (``--workers 0`` or ``1``) or one run with two
    worker processes at a time. The runs are pinned only when they fill the machine (no room for
    another run): asking for more jobs than fit shares the cores, and so does asking for fewer
    (``--jobs 1`` on two cores), since pinning would put every such sweep's run on the first
    core: two sweeps side by side on one core.
    """

    name = "local"

    def __init__(self, cores_per_run: int, jobs: int | None = None) -> None:
        cores = local_cores(cores_per_run)
        self.jobs = jobs or max(1, len(cores) // cores_per_run)
        self.spare = len(cores) - self.jobs * cores_per_run  # cores no run of this sweep holds
        self.pinned = 0 <= self.spare < cores_per_run
        self.cores_per_run = cores_per_run
        self._free: queue.Queue = queue.Queue()
        for i in range(self.jobs):
            chunk = cores[i * cores_per_run : (i + 1) * cores_per_run]
            self._free.put(chunk if self.pinned else None)
        self._pool = concurrent.futures.ThreadPoolExecutor(self.jobs, thread_name_prefix="run")
        self._stop = threading.Event()
        self._futures: dict[concurrent.futures.Future, RunJob] = {}

    def describe(self) -> str:
        """One phrase for the sweep's header line."""
        if self.pinned:
            share = "pinned"
        elif self.spare < 0:
            share = "shared, more jobs than cores"
        else:
            share = "not pinned, fewer jobs than cores: the system places them"
        return f"{self.jobs} at a time on this machine ({self.cores_per_run} core(s) each, {share})"

    def _execute(self, job: RunJob) -> dict[str, Any]:
        cores = self._free.get()
        try:
            return execute_job(job, cores, self._stop)
        finally:
            self._free.put(cores)

    def submit(self, job: RunJob) -> None:
        """Queue a run."""
        self._futures[self._pool.submit(self._execute, job)] = job

    def pending(self) -> int:
        """Runs queued or running."""
        return len(self._futures)

    def wait(self, timeout: float) -> list[dict[str, Any]]:
        """Wait up to ``timeout`` s; return the records of runs that ended meanwhile."""
        if not self._futures:
            return []
        done, _ = concurrent.futures.wait(
            self._futures, timeout, return_when=concurrent.futures.FIRST_COMPLETED
        )
        records = []
        for future in done:
            job = self._futures.pop(future)
            if future.cancelled():
                continue
            error = future.exception()
            records.append(
                _failed(job, f"{type(error).__name__}: {error}") if error else future.result()
            )
        return records

    def interrupt(self) -> None:
        """Stop: queued runs never start, running ones save a checkpoint and end."""
        self._stop.set()
        for future in self._futures:
            future.cancel()

    def close(self) -> None:
        """Wait for the runs still stopping."""
        self._pool.shutdown(wait=True, cancel_futures=True)


def _check_reachable(address: str) -> None:
    """Fail fast (Ray itself retries for minutes) when HOST:PORT does not answer."""
    host, sep, port = address.removeprefix("ray://").rpartition(":")
    if not sep or not port.isdigit():
        raise UsageError(f"--address must be auto, HOST:PORT or ray://HOST:PORT, got '{address}'")
    try:
        socket.create_connection((host, int(port)), timeout=5).close()
    except OSError as exc:
        raise UsageError(
            f"cannot reach the Ray cluster at {address}: {exc.strerror or exc}"
        ) from None


class RayExecutor:
    """Runs each run as a Ray task holding ``cores_per_run`` CPUs, anywhere in the cluster.

    ``address`` None starts a local Ray instance (or uses the one this process already
    started). The sweep folder must be on a file system every node sees at the same path.
    """

    name = "ray"

    def __init__(self, cores_per_run: int, address: str | None = None) -> None:
        try:
            import ray
        except ModuleNotFoundError:
            raise UsageError(
                "--executor ray needs Ray, which is not installed: pip install 'devlearn[ray]'"
            ) from None
        self.ray = ray
        self.started = False
        if not ray.is_initialized():
            if address is not None and address != "auto":
                _check_reachable(address)
            try:
                ray.init(address=address, include_dashboard=False, log_to_driver=False)
            except ConnectionError as exc:
                where = f"at {address}" if address else "(local instance)"
                raise UsageError(f"cannot reach a Ray cluster {where}: {exc}") from None
            self.started = address is None
        nodes = [n for n in ray.nodes() if n.get("Alive")]
        largest = max((n.get("Resources", {}).get("CPU", 0) for n in nodes), default=0)
        if cores_per_run > largest:
            self.close()
            raise UsageError(
                f"each run needs {cores_per_run} CPUs but the largest node of the Ray cluster "
                f"has {largest:g}; use fewer --workers or --cores"
            )
        self.cpus = sum(n.get("Resources", {}).get("CPU", 0) for n in nodes)
        self.cores_per_run = cores_per_run
        self._task = ray.remote(num_cpus=cores_per_run, max_retries=0)(execute_job)
        self._refs: dict[Any, RunJob] = {}
        self._cancelled = False

    def describe(self) -> str:
        """One phrase for the sweep's header line."""
        return (
            f"as Ray tasks of {self.cores_per_run} CPU(s) each "
            f"(cluster: {self.cpus:g} CPUs on {len(self.ray.nodes())} node(s))"
        )

    def submit(self, job: RunJob) -> None:
        """Queue a run as a task."""
        self._refs[self._task.remote(job)] = job

    def pending(self) -> int:
        """Runs queued or running."""
        return len(self._refs)

    def wait(self, timeout: float) -> list[dict[str, Any]]:
        """Wait up to ``timeout`` s; return the records of runs that ended meanwhile."""
        if not self._refs:
            return []
        ready, _ = self.ray.wait(list(self._refs), num_returns=len(self._refs), timeout=timeout)
        records = []
        for ref in ready:
            job = self._refs.pop(ref)
            try:
                records.append(self.ray.get(ref))
            except Exception as exc:  # cancelled, worker or node lost, task error
                if self._cancelled:  # what the task got to before it stopped
                    record = read_json(job.record_path) or {"name": job.name}
                    if record.get("status") != "done":
                        record["status"] = "interrupted"
                    records.append(record)
                else:
                    records.append(_failed(job, f"Ray task failed: {str(exc).splitlines()[0]}"))
        return records

    def interrupt(self) -> None:
        """Cancel every task: queued ones never start, running ones save a checkpoint."""
        self._cancelled = True
        for ref in self._refs:
            self.ray.cancel(ref)

    def close(self) -> None:
        """Wait for cancelled tasks to stop; shut down a local instance this started."""
        refs = list(getattr(self, "_refs", {}))
        if refs:
            self.ray.wait(refs, num_returns=len(refs), timeout=STOP_TIMEOUT_S)
        if self.started:
            self.ray.shutdown()


def make_executor(
    kind: str, cores_per_run: int, jobs: int | None, address: str | None
) -> LocalExecutor | RayExecutor:
    """The executor ``kind`` (local or ray); UsageError if it cannot run here."""
    if kind == "ray":
        if jobs is not None:
            raise UsageError("--jobs is for the local executor; Ray runs as many as fit")
        return RayExecutor(cores_per_run, address)
    return LocalExecutor(cores_per_run, jobs)
