"""One run of a sweep: train (or resume) and evaluate in subprocesses, keeping its record."""

from __future__ import annotations

import datetime
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from devlearn.api.errors import UsageError
from devlearn.api.json_files import read_json as read_json_file
from devlearn.config.resolve import RUN_CONFIG_FILE
from devlearn.files import InUseError, lock_exclusively, write_text_atomically

LOG_TAIL_LINES = 15
"""Lines of a failed run's log shown in its record and on the console."""
PARENT_ENV = "DEVLEARN_PARENT_PID"
"""Set by a sweep for the commands it starts: ``devlearn`` then gets SIGTERM when the sweep dies
(see :func:`devlearn.cli.follow_parent`), so no run outlives a killed sweep."""
STOP_GRACE_S = 2.0
"""After a stop request, how long a run may take to stop on its own (Ctrl-C reaches it
directly) before it is sent SIGTERM, which also makes ``devlearn run`` save a checkpoint."""
STOP_TIMEOUT_S = 120.0
"""How long a stopping run may take to write its checkpoint before it is killed."""


@dataclass
class RunJob:
    """Everything needed to execute one run, anywhere (picklable, for Ray tasks)."""

    name: str
    """The run's name (its folder name)."""
    behavior: str
    """Behaviour to train."""
    sweep_dir: str
    """Absolute path of the sweep folder (shared by every node that runs jobs)."""
    values: dict[str, str]
    """The run's grid values."""
    seed: int
    """The run's seed."""
    config: dict[str, Any]
    """The run's resolved config (:func:`~devlearn.config.run_config.to_dict`), written to
    ``RUN/run_config.json`` and started from (``devlearn run BEHAVIOR --config FILE``)."""
    settings: list[str]
    """What the run sets beyond the behaviour's defaults (seed, preset, ``--set`` items), as
    people read it in ``--dry-run`` and the record."""
    resume_args: list[str]
    """``devlearn run`` options of a resume (after ``run BEHAVIOR --resume DIR``)."""
    eval_args: list[str]
    """``devlearn eval`` options (after ``eval BEHAVIOR --checkpoint PATH --out DIR``)."""
    launcher: list[str] | None = None
    """Command prefix that starts devlearn (None: this Python with ``-m devlearn.cli``)."""
    global_args: list[str] = field(default_factory=list)
    """Options before the sub-command (``--disable-plugin NAME``)."""
    evals: dict[str, list[str]] = field(default_factory=dict)
    """Evaluations of the run: folder (in the run folder) -> ``devlearn eval`` options after
    ``--out FOLDER`` (empty: one, ``eval`` with :attr:`eval_args`). A restarted run skips an
    evaluation whose folder holds a readable eval.json."""
    trainer: list[str] | None = None
    """A training command other than ``devlearn run``: a script and its arguments, run with the
    executing process's Python (``examples/sb3/train.py ...``). It writes :attr:`policy` into
    the run folder; it cannot resume, so an interrupted one starts again."""
    policy: str | None = "checkpoint_latest.pt"
    """The file of the run folder the evaluations score; None: nothing is trained (baselines,
    whose evaluation options name the policy)."""

    @property
    def evaluations(self) -> dict[str, list[str]]:
        """Evaluation folder (in the run folder) -> its ``devlearn eval`` options."""
        return self.evals or {"eval": self.eval_args}

    @property
    def run_dir(self) -> Path:
        """The ``devlearn run`` folder: SWEEP/runs/NAME."""
        return Path(self.sweep_dir) / "runs" / self.name

    @property
    def config_path(self) -> Path:
        """The run's resolved config: SWEEP/runs/NAME/run_config.json."""
        return self.run_dir / RUN_CONFIG_FILE

    @property
    def record_path(self) -> Path:
        """The run's record: SWEEP/records/NAME.json."""
        return Path(self.sweep_dir) / "records" / f"{self.name}.json"

    @property
    def log_path(self) -> Path:
        """Output of every command of the run, appended: SWEEP/logs/NAME.log."""
        return Path(self.sweep_dir) / "logs" / f"{self.name}.log"


def resume_args(workers: int, total_steps: int) -> list[str]:
    """The ``devlearn run --resume`` options of a planned run (:attr:`RunJob.resume_args`): its
    worker count and its own budget, the resolved config's ``total_steps`` (``--steps``, or a
    ``total_steps=`` item that overrides it), so that a restart trains to where the run was
    meant to stop."""
    return ["--workers", str(workers), "--steps", str(total_steps)]


def write_json(path: Path, data: dict[str, Any]) -> None:
    """Write JSON atomically (a reader never sees half a file)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomically(path, json.dumps(data, indent=2, default=float) + "\n")


def read_json(path: Path) -> dict[str, Any] | None:
    """A JSON object from ``path``, or None if it is missing or unreadable (the guarded
    reader's refusals included: :func:`devlearn.api.json_files.read_json`)."""
    try:
        data = read_json_file(path)
    except UsageError:
        return None
    return data if isinstance(data, dict) else None


def code_version() -> dict[str, Any]:
    """The devlearn code this process runs: git commit (and whether it has local changes)."""
    import devlearn

    root = Path(devlearn.__file__).resolve().parents[1]
    info: dict[str, Any] = {"devlearn": devlearn.__version__, "commit": None, "dirty": None}
    try:
        git = ["git", "-C", str(root)]
        commit = subprocess.run([*git, "rev-parse", "HEAD"], capture_output=True, text=True)
        if commit.returncode == 0:
            info["commit"] = commit.stdout.strip()
            status = subprocess.run(
                [*git, "status", "--porcelain", "--untracked-files=no"],
                capture_output=True,
                text=True,
            )
            info["dirty"] = bool(status.stdout.strip())
    except OSError:  # no git: the version alone
        pass
    return info


def log_tail(path: Path, lines: int = LOG_TAIL_LINES) -> list[str]:
    """The last ``lines`` non-empty lines of a log (a progress bar's redraws count once)."""
    try:
        with open(path, "rb") as f:
            f.seek(max(f.seek(0, os.SEEK_END) - 64_000, 0))
            text = f.read().decode(errors="replace")
    except OSError:
        return []
    rows = [line.rsplit("\r", 1)[-1].rstrip() for line in text.split("\n")]
    return [r for r in rows if r.strip()][-lines:]


def has_checkpoint(run_dir: Path) -> bool:
    """Whether ``devlearn run --resume`` has a checkpoint to continue from."""
    return run_dir.is_dir() and any(run_dir.glob("checkpoint_*.pt"))


def _now() -> str:
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")


class _Run:
    """Executes one job; keeps its record on disk as it goes."""

    def __init__(self, job: RunJob, cores: list[int] | None, stop: threading.Event | None) -> None:
        self.job, self.cores, self.stop = job, cores, stop
        self.record = read_json(job.record_path) or {}
        self.record.update(
            name=job.name,
            values=job.values,
            seed=job.seed,
            run_dir=f"runs/{job.name}",
            log=f"logs/{job.name}.log",
            error=None,
            log_tail=[],
        )
        self.record.setdefault("attempts", [])
        self.record.setdefault("trained", False)
        self.interrupted = False

    def save(self, status: str) -> dict[str, Any]:
        self.record["status"] = status
        write_json(self.job.record_path, self.record)
        return self.record

    def command(self, phase: str, argv: list[str], lock_fd: int) -> int:
        """Run one command with its output appended to the log; return its exit code."""
        job = self.job
        version = code_version()
        attempt: dict[str, Any] = {
            "phase": phase,
            "argv": argv,
            "host": socket.gethostname(),
            "started": _now(),
        }
        attempt.update(commit=version["commit"], dirty=version["dirty"], cores=self.cores)
        self.record["attempts"].append(attempt)
        self.record["commit"] = version
        self.save("training" if phase != "eval" else "evaluating")
        job.log_path.parent.mkdir(parents=True, exist_ok=True)
        start = time.monotonic()
        with open(job.log_path, "ab") as log:
            log.write(f"=== {attempt['started']} {phase}: {' '.join(argv)}\n".encode())
            log.flush()
            proc = subprocess.Popen(
                argv,
                stdout=log,
                stderr=subprocess.STDOUT,
                stdin=subprocess.DEVNULL,
                pass_fds=(lock_fd,),  # the run stays locked while its process lives
                # the command ends (saving a checkpoint) when this sweep dies, even by SIGKILL
                env={**os.environ, PARENT_ENV: str(os.getpid())},
            )
            if self.cores:
                try:  # before the process starts its threads and workers, which inherit it
                    os.sched_setaffinity(proc.pid, self.cores)
                except (AttributeError, OSError):
                    pass
            returncode = self._wait(proc)
        attempt["wall_s"] = round(time.monotonic() - start, 3)
        attempt["returncode"] = returncode
        key = "eval_wall_s" if phase == "eval" else "train_wall_s"
        self.record[key] = round(self.record.get(key, 0.0) + attempt["wall_s"], 3)
        self.record["wall_s"] = round(
            self.record.get("train_wall_s", 0.0) + self.record.get("eval_wall_s", 0.0), 3
        )
        return returncode

    def _wait(self, proc: subprocess.Popen) -> int:
        asked = termed = None
        while True:
            try:
                return proc.wait(timeout=0.25)
            except subprocess.TimeoutExpired:
                pass
            except KeyboardInterrupt:  # a Ray cancel, or Ctrl-C in this process
                asked = asked or time.monotonic()
            if self.stop is not None and self.stop.is_set():
                asked = asked or time.monotonic()
            if asked is None:
                continue
            self.interrupted = True
            waited = time.monotonic() - asked
            if termed is None and waited > STOP_GRACE_S:
                proc.send_signal(signal.SIGTERM)
                termed = True
            elif waited > STOP_TIMEOUT_S:
                proc.kill()

    def fail(self, phase: str, returncode: int) -> dict[str, Any]:
        stopped = self.stop is not None and self.stop.is_set()
        if self.interrupted or stopped or returncode == 130:  # 130: devlearn's Ctrl-C exit
            return self.save("interrupted")
        self.record["error"] = f"exit code {returncode} while {phase}"
        self.record["log_tail"] = log_tail(self.job.log_path)
        return self.save("failed")

    def execute(self) -> dict[str, Any]:
        job = self.job
        base = list(job.launcher or [sys.executable, "-m", "devlearn.cli"]) + job.global_args
        job.record_path.parent.mkdir(parents=True, exist_ok=True)
        try:
            lock = lock_exclusively(job.record_path.with_suffix(".lock"), f"run {job.name}")
        except InUseError as exc:
            self.record["error"] = (
                f"{exc} (an earlier sweep's training still running?); stop it, then start the "
                "sweep again"
            )
            self.record["status"] = "failed"
            return self.record  # the record on disk belongs to the process holding it
        with lock:
            os.set_inheritable(lock.fileno(), True)
            if self.stop is not None and self.stop.is_set():  # stopped before it started
                return self.save("interrupted")
            if job.policy is not None and not self.record["trained"]:
                returncode = self.train(base, lock.fileno())
                if returncode != 0:
                    return self.fail("training", returncode)
                self.record["trained"] = True
            summaries = {}
            for folder, args in job.evaluations.items():
                out = job.run_dir / folder
                summary = read_json(out / "eval.json")  # a finished evaluation is kept
                if summary is None:
                    if self.stop is not None and self.stop.is_set():  # asked to stop
                        return self.save("interrupted")
                    argv = [*base, "eval", job.behavior]
                    if job.policy is not None:
                        argv += ["--checkpoint", str(job.run_dir / job.policy)]
                    argv += ["--out", str(out), *args]
                    returncode = self.command("eval", argv, lock.fileno())
                    if returncode != 0:
                        return self.fail("evaluating", returncode)
                    summary = read_json(out / "eval.json")
                summaries[folder] = summary
            self.record["config"] = read_json(job.run_dir / "config.json")
            if job.trainer is not None:
                self.record["train"] = read_json(job.run_dir / "train.json")
            self.record["eval"] = next(iter(summaries.values()), None)
            if job.evals:
                self.record["evals"] = summaries
            return self.save("done")

    def train(self, base: list[str], lock_fd: int) -> int:
        """Train: resume ``devlearn run`` from its checkpoint, else start afresh (from the
        resolved config, or the job's own trainer); the exit code."""
        job = self.job
        run_dir = str(job.run_dir)
        if job.trainer is None and has_checkpoint(job.run_dir):
            argv = [*base, "run", job.behavior, "--resume", run_dir, *job.resume_args]
            return self.command("resume", argv, lock_fd)
        if job.run_dir.exists():  # a start killed before its first checkpoint
            shutil.rmtree(job.run_dir)
        write_json(job.config_path, job.config)
        if job.trainer is not None:
            return self.command("train", [sys.executable, *job.trainer], lock_fd)
        argv = [*base, "run", job.behavior, "--out", run_dir, "--config", str(job.config_path)]
        return self.command("train", argv, lock_fd)


def execute_job(
    job: RunJob, cores: list[int] | None = None, stop: threading.Event | None = None
) -> dict[str, Any]:
    """Train (resuming from a checkpoint if the run has one) and evaluate one run.

    A run whose training finished earlier is only evaluated, and an evaluation whose eval.json
    is there is not run again. The record (``SWEEP/records/NAME.json``) is updated at every
    step: status, every command with its host, code commit, wall time and exit code, the final
    config and evaluation (``evals``: every evaluation's, by folder, when the job has several).

    Args:
        job: The run.
        cores: CPU cores to pin the run's processes to (None: no pinning).
        stop: When set, the running command is stopped (it saves a checkpoint first).
    Returns:
        The record; ``status`` is ``done``, ``failed`` (with ``error`` and ``log_tail``) or
        ``interrupted``.
    """
    return _Run(job, cores, stop).execute()
