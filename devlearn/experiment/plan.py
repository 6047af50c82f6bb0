"""plan_experiment(): every run of an experiment as a sweep job, every arm's config resolved and
every protocol checked, before anything starts.

Runs are named ``ARM,seed=S`` (an arm trained with one seed) and ``baseline_POLICY`` (a
baseline's evaluations, nothing trained); each run's evaluation under protocol ``P`` is written
to ``OUT/runs/NAME/eval_P/``.
"""

from __future__ import annotations

import importlib.util
import shlex
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from devlearn.api.errors import UsageError
from devlearn.experiment.spec import Arm, ExperimentSpec, Protocol
from devlearn.sweep.experiment import checked_config
from devlearn.sweep.job import RunJob, read_json, resume_args

if TYPE_CHECKING:
    from devlearn.evaluation.evaluate import EvalRequest
    from devlearn.plugins import PluginRegistry

SB3_ALGOS = {"sb3_ppo": "ppo", "sb3_sac": "sac"}
"""Learner -> ``examples/sb3/train.py --algo``."""
CHECKPOINT = "checkpoint_latest.pt"
"""What a devlearn arm's evaluations score: its run's final checkpoint."""
SCRIPTED_POLICY = "policy.pt"
"""What an SB3 arm's evaluations score: the scripted policy train.py writes."""


def sb3_script() -> Path:
    """``examples/sb3/train.py`` of the source tree devlearn runs from."""
    import devlearn

    return Path(devlearn.__file__).resolve().parents[1] / "examples" / "sb3" / "train.py"


def run_name(arm: str, seed: int) -> str:
    """The run of ``arm`` with ``seed``: ``devlearn_ppo,seed=1`` (its folder, record, log)."""
    return f"{arm},seed={seed}"


def baseline_name(policy: str) -> str:
    """The run holding baseline ``policy``'s evaluations: ``baseline_zero``."""
    return f"baseline_{policy}"


@dataclass
class PlannedRun:
    """A run of the experiment: an arm's seed, or a baseline."""

    job: RunJob
    """What the executor runs (training, then one evaluation per protocol)."""
    total_steps: int
    """Training budget (environment steps; 0 for a baseline)."""
    arm: Arm | None
    """The arm (None: a baseline)."""
    seed: int | None
    """The training seed (None: a baseline)."""


@dataclass
class ExperimentPlan:
    """An experiment checked and laid out in its folder."""

    spec: ExperimentSpec
    """The experiment file."""
    out: Path
    """The experiment folder."""
    runs: list[PlannedRun]
    """Baselines first, then every arm's runs, seeds outermost (an experiment stopped early
    still holds a complete comparison of its first seeds)."""

    @property
    def trained(self) -> list[PlannedRun]:
        """The runs that train."""
        return [r for r in self.runs if r.arm is not None]


def eval_args(
    protocol: Protocol,
    workers: int,
    baseline: str | None = None,
    baseline_overrides: tuple[str, ...] = (),
) -> list[str]:
    """``devlearn eval`` options of one evaluation under ``protocol`` (after ``--out``): a
    trained policy's (``--action``), or ``baseline``'s (``--policy``, and the experiment's
    ``baseline_set`` items after the protocol's)."""
    args = ["--policy", baseline] if baseline else []
    args += ["--episodes", str(protocol.episodes), "--seed", str(protocol.seed)]
    args += ["--start", protocol.start, "--workers", str(workers), "--json"]
    if baseline is None:
        args += ["--action", protocol.action]
    if protocol.session_s is not None:
        args += ["--session", f"{protocol.session_s:.12g}"]
    for item in (*protocol.overrides, *(baseline_overrides if baseline else ())):
        args += ["--set", item]
    return args


def _eval_request(
    behavior: str, protocol: Protocol, policy: str, baseline_overrides: tuple[str, ...] = ()
) -> EvalRequest:
    """``devlearn eval``'s request (checked when made) of an evaluation under ``protocol``
    (a baseline's with the experiment's ``baseline_set`` items)."""
    from devlearn.evaluation.evaluate import EvalRequest

    return EvalRequest(
        behavior,
        checkpoint=SCRIPTED_POLICY if policy == "checkpoint" else None,
        policy=policy,
        episodes=protocol.episodes,
        seed=protocol.seed,
        start=protocol.start,
        action=protocol.action if policy == "checkpoint" else "mean",
        overrides=(*protocol.overrides, *(baseline_overrides if policy != "checkpoint" else ())),
        session=protocol.session_s,
    )


def _check_protocols(spec: ExperimentSpec, registry: PluginRegistry) -> None:
    """Every protocol as ``devlearn eval`` checks it, for a trained policy and each baseline;
    its ``set`` items as the config pipeline resolves them."""
    from devlearn.config.resolve import RunRequest, resolve_config

    scripted = [a.name for a in spec.arms if a.learner in SB3_ALGOS]
    for protocol in spec.protocols:
        where = f"experiment file {spec.path}: protocols '{protocol.name}'"

        try:
            _eval_request(spec.behavior, protocol, "checkpoint")
            for baseline in spec.baselines:
                _eval_request(spec.behavior, protocol, baseline, spec.baseline_overrides)
            if protocol.overrides:
                resolve_config(RunRequest(spec.behavior, list(protocol.overrides)), registry)
            if spec.baselines and spec.baseline_overrides:
                items = [*protocol.overrides, *spec.baseline_overrides]
                resolve_config(RunRequest(spec.behavior, items), registry)
        except UsageError as exc:
            raise UsageError(f"{where}: {exc}") from None
        if protocol.action != "mean" and scripted:
            raise UsageError(
                f"{where}: action '{protocol.action}' needs a devlearn checkpoint; arm "
                f"'{scripted[0]}' "
                "writes a scripted policy, which acts with one deterministic action"
            )


def _check_sessions(spec: ExperimentSpec, action_repeat: int, name: str) -> None:
    """Every protocol's ``session_s`` a whole number of the run's decisions (as ``devlearn
    eval --session`` checks it for the policy the run writes)."""
    from devlearn.timing import decision_rate_error, physics_steps

    for protocol in spec.protocols:
        if protocol.session_s is None:
            continue
        if error := decision_rate_error(action_repeat, physics_steps(protocol.session_s)):
            raise UsageError(
                f"experiment file {spec.path}: protocols '{protocol.name}' session_s "
                f"{protocol.session_s:g} for run {name}: {error}"
            )


def _check_sb3(spec: ExperimentSpec, arm: Arm) -> None:
    where = f"experiment file {spec.path}: arms '{arm.name}'"
    if not sb3_script().is_file():
        raise UsageError(
            f"{where}: learner {arm.learner} runs {sb3_script()}, which is not here (it comes "
            "with devlearn's source tree)"
        )
    if importlib.util.find_spec("stable_baselines3") is None:
        raise UsageError(
            f"{where}: learner {arm.learner} needs Stable-Baselines3, which is not installed: "
            "pip install 'devlearn[sb3]'"
        )


def _arm_run(
    spec: ExperimentSpec,
    out: Path,
    arm: Arm,
    seed: int,
    registry: PluginRegistry,
    global_args: list[str],
) -> PlannedRun:
    from devlearn.config.resolve import RunRequest
    from devlearn.config.run_config import to_dict

    train = spec.train
    name = run_name(arm.name, seed)
    run_dir = out / "runs" / name
    shared = [*train.overrides, *arm.overrides]  # the arm's own win
    # A fixed thread count, not the automatic plan: a run trains the same numbers anywhere
    overrides = [f"torch_threads={train.threads}", *shared]
    top = {"total_steps": train.steps, "num_envs": train.envs, "workers": train.workers}
    request = RunRequest(spec.behavior, overrides, arm.preset, {**top, "seed": seed})
    cfg = checked_config(request, registry, name)
    _check_sessions(spec, cfg.env.action_repeat, name)
    cfg.out_dir = str(run_dir)
    trainer = None
    if arm.learner in SB3_ALGOS:
        trainer = [str(sb3_script()), "--algo", SB3_ALGOS[arm.learner]]
        trainer += ["--behavior", spec.behavior, "--steps", str(cfg.total_steps)]
        trainer += ["--seed", str(seed), "--envs", str(cfg.num_envs)]
        trainer += ["--workers", str(train.workers), "--threads", str(cfg.torch_threads)]
        trainer += ["--out", str(run_dir)]
        for item in shared:
            trainer += ["--set", item]
    settings = [f"seed={seed}", *([f"preset={arm.preset}"] if arm.preset else []), *overrides]
    job = RunJob(
        name=name,
        behavior=spec.behavior,
        sweep_dir=str(out),
        values={"arm": arm.name, "learner": arm.learner},
        seed=seed,
        config=to_dict(cfg),
        settings=[f"learner={arm.learner}", *settings] if trainer else settings,
        resume_args=resume_args(train.workers, cfg.total_steps),
        eval_args=[],
        launcher=spec.launcher,
        global_args=list(global_args),
        evals={p.folder: eval_args(p, train.workers) for p in spec.protocols},
        trainer=trainer,
        policy=SCRIPTED_POLICY if trainer else CHECKPOINT,
    )
    return PlannedRun(job, cfg.total_steps, arm, seed)


def _baseline_run(
    spec: ExperimentSpec, out: Path, policy: str, global_args: list[str]
) -> PlannedRun:
    workers = spec.train.workers
    job = RunJob(
        name=baseline_name(policy),
        behavior=spec.behavior,
        sweep_dir=str(out),
        values={"baseline": policy},
        seed=0,
        config={},
        settings=[f"policy={policy}"],
        resume_args=[],
        eval_args=[],
        launcher=spec.launcher,
        global_args=list(global_args),
        evals={
            p.folder: eval_args(
                p, workers, baseline=policy, baseline_overrides=spec.baseline_overrides
            )
            for p in spec.protocols
        },
        policy=None,
    )
    return PlannedRun(job, 0, None, None)


def plan_experiment(
    spec: ExperimentSpec,
    out: str | Path,
    registry: PluginRegistry,
    global_args: list[str] | None = None,
) -> ExperimentPlan:
    """Every run of the experiment in folder ``out``, checked as ``devlearn run`` and
    ``devlearn eval`` would check it: each arm x seed's config resolved through
    :func:`~devlearn.config.resolve.resolve_config` (the run starts from it), each protocol
    for a trained policy and for each baseline, each learner installed.

    Args:
        spec: The experiment file, read.
        out: The experiment folder (nothing is written here).
        registry: Plugin registry.
        global_args: ``devlearn`` options of every command (``--disable-plugin NAME``).
    Raises:
        UsageError: One line naming the file's key or the run, and what is valid.
    """
    registry.behavior(spec.behavior)  # unknown behaviour: one line naming the installed ones
    folder = Path(out).resolve()
    for arm in spec.arms:
        if arm.learner in SB3_ALGOS:
            _check_sb3(spec, arm)
    _check_protocols(spec, registry)
    extra = list(global_args or [])
    runs = [_baseline_run(spec, folder, policy, extra) for policy in spec.baselines]
    for seed in spec.seeds:
        runs += [_arm_run(spec, folder, arm, seed, registry, extra) for arm in spec.arms]
    return ExperimentPlan(spec, folder, runs)


def describe_plan(plan: ExperimentPlan) -> list[str]:
    """The commands of every run, as ``--dry-run`` lists them; steps an earlier start finished
    are marked ``(done)``."""
    lines = []
    for run in plan.runs:
        job = run.job
        record = read_json(job.record_path) or {}
        devlearn = ["devlearn", *job.global_args]
        if job.trainer is not None:
            argv = ["python", *job.trainer]
        elif job.policy is not None:
            argv = [*devlearn, "run", job.behavior, "--out", str(job.run_dir)]
            argv += ["--config", str(job.config_path)]
        else:
            argv = []
        if argv:
            done = "  (done)" if record.get("trained") else ""
            lines.append(f"{job.name}: {shlex.join(argv)}  # {' '.join(job.settings)}{done}")
        else:
            lines.append(f"{job.name}: nothing to train  # {' '.join(job.settings)}")
        for folder, args in job.evaluations.items():
            argv = [*devlearn, "eval", job.behavior]
            if job.policy is not None:
                argv += ["--checkpoint", str(job.run_dir / job.policy)]
            argv += ["--out", str(job.run_dir / folder), *args]
            done = "  (done)" if read_json(job.run_dir / folder / "eval.json") else ""
            lines.append(f"    {folder}: {shlex.join(argv)}{done}")
    return lines
