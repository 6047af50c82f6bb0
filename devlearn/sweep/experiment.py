"""run_sweep(): check everything, then train and evaluate every run, then write the report;
execute_runs(), the loop over a folder's runs that experiments (devlearn.experiment) share."""

from __future__ import annotations

import copy
import shutil
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from devlearn.api.errors import UsageError
from devlearn.files import NAME_MAX
from devlearn.sweep.bookkeeping import RunFolder, SweepFolder, check_folder
from devlearn.sweep.executors import LocalExecutor, RayExecutor, make_executor
from devlearn.sweep.job import RunJob, resume_args
from devlearn.sweep.progress import Progress
from devlearn.sweep.spec import SweepSpec, Variant, variants

if TYPE_CHECKING:
    from devlearn.config.resolve import RunRequest
    from devlearn.config.run_config import RunConfig
    from devlearn.plugins import PluginRegistry

POLL_S = 1.0
"""Seconds between two looks at the running runs."""


@dataclass
class PlannedRun:
    """A run of the sweep with its checked config."""

    variant: Variant
    """Grid values and seed."""
    job: RunJob
    """What the executor runs."""
    total_steps: int
    """The run's training budget (environment steps)."""


def plan_sweep(
    spec: SweepSpec, registry: PluginRegistry, global_args: list[str] | None = None
) -> list[PlannedRun]:
    """Every run of the sweep, each config resolved and checked as ``devlearn run`` would
    (:func:`~devlearn.config.resolve.resolve_config`); the job carries that config, which
    the run starts from (``devlearn run --config RUN/run_config.json``).

    Raises:
        UsageError: An unknown behaviour, grid key or value, a value the behaviour rejects (the
            run is named), or a launcher that is not installed.
    """
    from devlearn.config.resolve import RunRequest, resolve_config
    from devlearn.config.run_config import to_dict
    from devlearn.config.values import in_table, valid_keys

    train = spec.train
    base = resolve_config(RunRequest(spec.behavior), registry)
    keys = valid_keys(base)
    for key in spec.grid:
        if key not in keys and not in_table(base, key):  # learned.TERM.OPTION
            raise UsageError(
                f"--grid: unknown config key '{key}'; valid keys: {', '.join(keys)} "
                "(and learned.TERM.OPTION for a learned reward in curiosity)"
            )
    runs = []
    for variant in variants(spec.grid, spec.seeds):
        overrides = [*train.overrides, *variant.overrides]
        if not any(item.partition("=")[0].strip() == "torch_threads" for item in overrides):
            # A fixed thread count (the run's cores), not the automatic plan: a run then trains
            # the same numbers under either executor and on any machine.
            overrides.append(f"torch_threads={train.cores_per_run}")
        top = {"total_steps": train.steps, "num_envs": train.envs, "workers": train.workers}
        request = RunRequest(
            spec.behavior, overrides, train.preset or "", {**top, "seed": variant.seed}
        )
        run_dir = spec.out.resolve() / "runs" / variant.name
        if len(variant.name.encode()) > NAME_MAX:
            raise UsageError(
                f"run {variant.name[:40]}...: its folder name would be "
                f"{len(variant.name.encode())} bytes, over the file system's {NAME_MAX}; "
                "give shorter --grid values"
            )
        cfg = checked_config(request, registry, variant.name)
        cfg.out_dir = str(run_dir)
        ev = spec.evaluation
        eval_args = ["--episodes", str(ev.episodes), "--seed", str(ev.seed), "--json", *ev.args]
        job = RunJob(
            name=variant.name,
            behavior=spec.behavior,
            sweep_dir=str(spec.out.resolve()),
            values=dict(variant.values),
            seed=variant.seed,
            config=to_dict(cfg),
            settings=_settings(variant.seed, train.preset, overrides),
            resume_args=resume_args(train.workers, cfg.total_steps),
            eval_args=eval_args,
            launcher=spec.launcher,
            global_args=list(global_args or []),
        )
        runs.append(PlannedRun(variant, job, cfg.total_steps))
    if spec.launcher and shutil.which(spec.launcher[0]) is None:
        raise UsageError(f"launcher command '{spec.launcher[0]}' is not found")
    return runs


def checked_config(request: RunRequest, registry: PluginRegistry, name: str) -> RunConfig:
    """A run's config resolved and checked as ``devlearn run`` would check it: the behaviour
    built on it, the options of its learned rewards too.

    Raises:
        UsageError: What the config pipeline refuses, naming the run (``run NAME: ...``).
    """
    from devlearn.config.resolve import resolve_config
    from devlearn.training.learned_rewards import LearnedRewards

    try:
        cfg = resolve_config(request, registry)
        registry.create(request.behavior, cfg.behavior)
        LearnedRewards.from_config(copy.deepcopy(cfg), registry)  # learned.* options too
    except UsageError as exc:
        raise UsageError(f"run {name}: {exc}") from None
    return cfg


def _settings(seed: int, preset: str | None, overrides: list[str]) -> list[str]:
    """What a run sets beyond the behaviour's defaults, for people: ``seed=4``,
    ``preset=paper``, then its ``--set`` items."""
    return [f"seed={seed}", *([f"preset={preset}"] if preset else []), *overrides]


def write_sweep_report(run_dirs: list[Path], out_dir: Path) -> dict[str, Any]:
    """``devlearn report`` over the evaluated runs, into ``out_dir`` (report.md, report.png)."""
    from devlearn.evaluation.report import write_report

    return write_report(run_dirs, out_dir)


def run_sweep(
    spec: SweepSpec,
    registry: PluginRegistry,
    *,
    global_args: list[str] | None = None,
    command: str = "",
    stream: TextIO | None = None,
) -> int:
    """Run a sweep: train and evaluate every run not done yet, then write the report.

    Everything that can be checked is checked before anything starts (configs, executor,
    folder). Finished runs are kept, unfinished ones continue from their checkpoint, a failed
    run is reported with its log's last lines and the others go on.

    Args:
        spec: The sweep.
        registry: Plugin registry.
        global_args: ``devlearn`` options for every command (``--disable-plugin``).
        command: The command line, recorded in sweep.json.
        stream: Where progress lines go (default stdout).
    Returns:
        0 when every run is done and the report written (or not asked for), else 1.
    Raises:
        UsageError: Bad input (nothing was started).
        KeyboardInterrupt: Ctrl-C or SIGTERM; running runs saved a checkpoint.
    """
    stream = stream or sys.stdout
    runs = plan_sweep(spec, registry, global_args)
    saved = check_folder(spec)
    executor = make_executor(spec.executor, spec.train.cores_per_run, spec.jobs, spec.address)
    try:
        folder = SweepFolder(spec, saved, command)
    except BaseException:
        executor.close()
        raise
    headline = registry.behavior(spec.behavior).about.headline_metric
    print(
        f"sweep {spec.out}: {len(runs)} runs of {spec.behavior}, {executor.describe()}", file=stream
    )
    progress = Progress(len(runs), headline, stream)
    try:
        totals = {run.job.name: run.total_steps for run in runs}
        records = execute_runs([run.job for run in runs], totals, folder, executor, progress)
        return _finish(spec, runs, records, stream)
    finally:
        progress.close()
        folder.close()


def execute_runs(
    jobs: list[RunJob],
    totals: dict[str, int],
    folder: RunFolder,
    executor: LocalExecutor | RayExecutor,
    progress: Progress,
) -> dict[str, dict[str, Any]]:
    """Hand every job not done yet to the executor and wait for them all, keeping runs.json
    and the progress lines up to date; the executor is closed at the end.

    Args:
        jobs: The runs, in the folder's order.
        totals: Each run's training budget (environment steps; 0: nothing to train).
        folder: The open folder (records of earlier starts, runs.json).
        executor: Where the runs execute.
        progress: Where their states are shown.
    Returns:
        Every run's record by name (``status``: done, failed or interrupted).
    Raises:
        KeyboardInterrupt: Ctrl-C or SIGTERM; running runs saved a checkpoint, queued ones never
            started.
    """
    records: dict[str, dict[str, Any]] = {}
    active = []
    for job in jobs:
        record = folder.finished_record(job)
        if record is not None:
            records[job.name] = record
            progress.earlier(record)
            continue
        folder.mark_queued(job)
        progress.line("queued", job.name)
        try:
            executor.submit(job)
        except BaseException:  # an interrupt while queueing: stop what was queued
            executor.interrupt()
            executor.close()
            raise
        active.append(job)

    def collect(timeout: float) -> None:
        for record in executor.wait(timeout):
            records[record["name"]] = record
            progress.finished(record, folder.path)
        folder.write_runs([records[job.name] for job in jobs if job.name in records])

    try:
        while executor.pending():
            collect(POLL_S)
            active = [job for job in active if job.name not in records]
            progress.tick(active, totals)
    except BaseException:
        # Ctrl-C, SIGTERM or any error: running runs save a checkpoint; queued ones never
        # start (a sweep that stopped must not go on starting runs and evaluations)
        executor.interrupt()
        executor.close()
        collect(0)
        raise
    executor.close()
    return records


def _finish(spec: SweepSpec, runs: list[PlannedRun], records: dict, stream: TextIO) -> int:
    """Summary line, then the report over the evaluated runs."""
    done = [r for r in runs if records.get(r.job.name, {}).get("status") == "done"]
    failed = [r.job.name for r in runs if records.get(r.job.name, {}).get("status") != "done"]
    print(f"{len(done)} of {len(runs)} runs done and evaluated in {spec.out / 'runs'}", file=stream)
    if failed:
        print(
            f"not done: {', '.join(failed)}; start the same command again to retry them "
            "(finished runs are kept, unfinished ones continue from their checkpoints)",
            file=stream,
        )
    if not spec.report:
        return 1 if failed else 0
    if not done:
        print("devlearn: error: no run finished, so there is no report", file=sys.stderr)
        return 1
    try:
        write_sweep_report([r.job.run_dir for r in done], spec.out / "report")
    except UsageError as exc:
        print(f"devlearn: error: report step failed: {exc}", file=sys.stderr)
        return 1
    print(f"report: {spec.out / 'report' / 'report.md'}", file=stream)
    return 1 if failed else 0
