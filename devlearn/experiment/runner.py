"""run_experiment(): check everything, then train every arm x seed and evaluate it under every
protocol, with the baselines, on the sweep's executors and bookkeeping.

Layout of an experiment folder::

    OUT/experiment.json      what decides the numbers, the commit, every start (command, commit,
                             the file's digest)
    OUT/experiment.toml      the experiment file
    OUT/runs.json            every run's record (status, commands, wall time, commit, results)
    OUT/records/NAME.json    one run's record, written as the run goes
    OUT/logs/NAME.log        the output of every command of one run
    OUT/runs/ARM,seed=S/     a training run (devlearn run, or train.py), eval_PROTOCOL/ in it
    OUT/runs/baseline_P/     baseline P's evaluations, eval_PROTOCOL/
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from devlearn.api.errors import UsageError
from devlearn.experiment.plan import ExperimentPlan, plan_experiment
from devlearn.experiment.spec import ExperimentSpec
from devlearn.files import write_text_atomically
from devlearn.sweep.bookkeeping import RunFolder, differences, now, saved_info
from devlearn.sweep.executors import make_executor
from devlearn.sweep.experiment import execute_runs
from devlearn.sweep.job import code_version
from devlearn.sweep.progress import Progress

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry

EXPERIMENT_INFO = "experiment.json"
"""What an experiment folder holds (the folder's mark)."""
EXPERIMENT_COPY = "experiment.toml"
"""The experiment file, as last started."""


def check_experiment_folder(spec: ExperimentSpec, out: Path) -> dict[str, Any] | None:
    """Check that ``out`` can hold this experiment, before anything is written.

    A folder started with this experiment restarts it: its arms and protocols must be as they
    were (their numbers would mix otherwise); arms, protocols, seeds and baselines may be
    added.

    Returns:
        The folder's experiment.json when it holds this experiment already, else None.
    Raises:
        UsageError: A file; a folder holding something else; another behaviour; an arm, a
            protocol or the training settings changed.
    """
    saved = saved_info(out, EXPERIMENT_INFO, "experiment")
    if saved is None:
        return None
    what = saved.get("what", {})
    if what.get("behavior") != spec.behavior:
        raise UsageError(
            f"experiment folder {out} holds an experiment of '{what.get('behavior')}', not "
            f"'{spec.behavior}'; give another OUT"
        )
    new = spec.what()
    changed = differences(what.get("train"), new["train"], "train.")
    changed += differences(
        {"baseline_set": what.get("baseline_set", [])},
        {"baseline_set": new.get("baseline_set", [])},
    )
    for section in ("arms", "protocols"):
        old = what.get(section) or {}
        for name, settings in new[section].items():
            if name in old:
                changed += differences(old[name], settings, f"{section}.{name}.")
    if changed:
        raise UsageError(
            f"experiment folder {out} was started with other settings ({'; '.join(changed)}); "
            "restart it with the same ones (arms, protocols, seeds and baselines may be added), "
            "or give another OUT"
        )
    return saved


class ExperimentFolder(RunFolder):
    """An open experiment folder: experiment.json, the experiment file, the runs' records."""

    def __init__(
        self, spec: ExperimentSpec, out: Path, saved: dict[str, Any] | None, command: str
    ) -> None:
        version = code_version()
        info = saved or {
            "name": spec.name,
            "created": now(),
            "commit": version,
            "starts": [],
        }
        what = spec.what()
        for section in ("arms", "protocols"):  # those of earlier starts are kept
            what[section] = {**(info.get("what") or {}).get(section, {}), **what[section]}
        info.update(
            what=what,
            seeds=spec.seeds,
            baselines=spec.baselines,
            file=EXPERIMENT_COPY,
        )
        start = {"time": now(), "command": command, "commit": version}
        info.setdefault("starts", []).append({**start, "file_sha256": spec.sha256})
        super().__init__(out, "experiment", EXPERIMENT_INFO, info)
        write_text_atomically(out / EXPERIMENT_COPY, spec.text)
        self.first_commit = (info.get("commit") or {}).get("commit")
        self.commit = version.get("commit")


def run_experiment(
    spec: ExperimentSpec,
    out: str | Path,
    registry: PluginRegistry,
    *,
    jobs: int | None = None,
    executor: str | None = None,
    address: str | None = None,
    global_args: list[str] | None = None,
    command: str = "",
    stream: TextIO | None = None,
) -> int:
    """Run an experiment: train and evaluate every run not done yet.

    Everything that can be checked is checked before anything starts (configs, protocols,
    learners, executor, folder). Finished steps are kept (a trained run is not trained again,
    an evaluation with its eval.json is not run again), an interrupted ``devlearn run``
    continues from its checkpoint; a failed run is reported with its log's last lines and the
    others go on.

    Args:
        spec: The experiment file, read.
        out: The experiment folder.
        registry: Plugin registry.
        jobs: Local executor: runs at a time (None: the file's, else as many as fit).
        executor: ``local`` or ``ray`` (None: the file's).
        address: Ray executor: the cluster (None: the file's, else a local instance).
        global_args: ``devlearn`` options of every command (``--disable-plugin``).
        command: The command line, recorded in experiment.json.
        stream: Where progress lines go (default stdout).
    Returns:
        0 when every run is done and evaluated, else 1.
    Raises:
        UsageError: Bad input (nothing was started).
        KeyboardInterrupt: Ctrl-C or SIGTERM; running runs saved a checkpoint.
    """
    stream = stream or sys.stdout
    plan = plan_experiment(spec, out, registry, global_args)
    saved = check_experiment_folder(spec, plan.out)
    kind = executor or spec.executor
    if jobs is None and kind == "local":  # the file's jobs are the local executor's
        jobs = spec.jobs
    address = address or spec.address
    if kind == "local" and address is not None:
        raise UsageError("--address is for --executor ray")
    runner = make_executor(kind, spec.train.cores_per_run, jobs, address)
    try:
        folder = ExperimentFolder(spec, plan.out, saved, command)
    except BaseException:
        runner.close()
        raise
    trained = len(plan.trained)
    print(
        f"experiment {spec.name} in {plan.out}: {trained} runs ({len(spec.arms)} arms x "
        f"{len(spec.seeds)} seeds) and {len(spec.baselines)} baseline(s) of {spec.behavior}, "
        f"each evaluated under {len(spec.protocols)} protocol(s); {runner.describe()}",
        file=stream,
    )
    if folder.first_commit and folder.commit != folder.first_commit:
        print(
            f"note: {plan.out} was started on commit {folder.first_commit[:12]}; this start runs "
            f"{str(folder.commit)[:12]} (each run's record keeps the commit of every command)",
            file=stream,
        )
    headline = registry.behavior(spec.behavior).about.headline_metric
    progress = Progress(len(plan.runs), headline, stream)
    try:
        totals = {run.job.name: run.total_steps for run in plan.runs}
        records = execute_runs([r.job for r in plan.runs], totals, folder, runner, progress)
        return _finish(plan, records, stream)
    finally:
        progress.close()
        folder.close()


def _finish(plan: ExperimentPlan, records: dict[str, dict[str, Any]], stream: TextIO) -> int:
    names = [run.job.name for run in plan.runs]
    failed = [n for n in names if records.get(n, {}).get("status") != "done"]
    print(
        f"{len(names) - len(failed)} of {len(names)} runs done and evaluated in "
        f"{plan.out / 'runs'}",
        file=stream,
    )
    if failed:
        print(
            f"not done: {', '.join(failed)}; start the same command again to retry them "
            "(finished steps are kept, unfinished runs continue from their checkpoints)",
            file=stream,
        )
        return 1
    print(
        f"next: devlearn experiment publish {plan.out} DEST, then devlearn experiment table DEST",
        file=stream,
    )
    return 0
