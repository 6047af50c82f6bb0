"""Experiment files (TOML): what an experiment trains, how it evaluates, what it compares with.

An experiment file declares everything that decides its numbers; ``devlearn experiment run
FILE OUT`` runs it, ``publish`` keeps what a reader needs, ``table`` tabulates it
(docs/experiments.md)::

    name = "learners"                 # default: the file's name
    behavior = "self_touch"
    description = "devlearn's PPO against SB3's PPO"
    seeds = [1, 2, 3]                 # or "1-3"
    baselines = ["zero", "random"]    # evaluated once per protocol (also: held_random)
    baseline_set = []                 # --set items of every baseline's evaluation

    [train]                           # every arm x seed
    steps = 2_048_000
    envs = 16
    workers = 0
    torch_threads = 1
    set = { "behavior.curriculum" = "two_stage" }   # every devlearn arm's, under its own

    [[arms]]
    name = "devlearn_ppo"             # devlearn run with the behaviour's defaults

    [[arms]]
    name = "paper"
    preset = "paper"
    set = ["ppo.learning_rate=1e-4"]

    [[arms]]
    name = "sb3_ppo"
    learner = "sb3_ppo"               # examples/sb3/train.py

    [[protocols]]
    name = "random_mean"              # its evaluation folders are eval_random_mean
    start = "stage"                   # stage, babybench, rest, random
    episodes = 100
    seed = 0
    action = "mean"                   # or sample
    set = { "infant.age_months" = 6 }

    [[protocols]]
    name = "sessions"                 # whole 5-minute sessions from rest (devlearn eval --session)
    start = "rest"
    episodes = 10                     # sessions
    session_s = 300

    [[references]]
    source = "the paper, Table II"
    protocol = "random_mean"          # default: the first protocol
    rows = [{ label = "Model I", value = 0.65, low = 0.6, high = 0.7 }]

    [[references]]                    # figures for --metric columns, in the source's words
    source = "DiMercurio et al. 2018, abstract"
    protocol = "sessions"
    rows = [{ label = "infants", metrics = { "likeness_coded.touches_per_minute" = "<= 40" } }]

    [executor]                        # how, not what: may change between starts
    kind = "local"
    jobs = 2

Reading a file checks its shape (keys, kinds of values, names); :func:`plan_experiment
<devlearn.experiment.plan.plan_experiment>` then resolves every arm's config as ``devlearn run``
would and checks every protocol as ``devlearn eval`` would.
"""

from __future__ import annotations

import hashlib
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from devlearn.api.errors import UsageError
from devlearn.config.checks import ENVS_MAX, SEED_MAX, STEPS_MAX, THREADS_MAX
from devlearn.sweep.spec import parse_seeds, value_text
from devlearn.sweep.sweep_file import EXECUTORS, load_toml

LEARNERS = {
    "devlearn": "devlearn's PPO (devlearn run)",
    "sb3_ppo": "Stable-Baselines3's PPO (examples/sb3/train.py --algo ppo)",
    "sb3_sac": "Stable-Baselines3's SAC (examples/sb3/train.py --algo sac)",
}
"""Who trains an arm: ``learner = NAME``."""
BASELINES = ("zero", "random", "held_random")
"""``devlearn eval --policy`` baselines an experiment can evaluate."""
STARTS = ("stage", "babybench", "rest", "random")
"""``devlearn eval --start`` values (checked again by ``devlearn eval`` itself at plan time)."""
ACTIONS = ("mean", "sample", "expected_clipped")
"""``devlearn eval --action`` values."""
KEYS = {
    "": {
        "name", "behavior", "description", "seeds", "baselines", "baseline_set", "train", "arms",
        "protocols", "references", "executor",
    },
    "train": {"steps", "envs", "workers", "torch_threads", "cores", "set"},
    "arms": {"name", "learner", "set", "preset", "note"},
    "protocols": {"name", "start", "episodes", "seed", "action", "session_s", "set"},
    "references": {"source", "protocol", "note", "rows"},
    "rows": {"label", "value", "low", "high", "metrics"},
    "executor": {"kind", "jobs", "address", "launcher"},
}  # fmt: skip
"""Valid keys of each table ("" is the top level; ``rows`` are a reference's)."""
SAFE_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.+-]*")
"""Arm and protocol names: they name folders."""
NAME_MAX = 100
"""Longest arm or protocol name."""
EPISODES_MAX = 1_000_000
"""Most episodes of one evaluation (as ``devlearn eval --episodes``)."""
SESSION_S_MAX = 86_400.0
"""Longest ``session_s``: a simulated day (seconds), as ``devlearn eval --session``."""
CORES_MAX = 4_096
"""Most workers, cores or jobs (as ``devlearn sweep``)."""


@dataclass(frozen=True)
class Arm:
    """One way of training: a learner with its settings, trained once per seed."""

    name: str
    """The arm's name (its runs' folders: ``NAME,seed=S``)."""
    learner: str = "devlearn"
    """One of :data:`LEARNERS`."""
    overrides: tuple[str, ...] = ()
    """``key=value`` config overrides (``--set``), after the experiment's ``[train] set``."""
    preset: str = ""
    """The behaviour preset the arm starts from (devlearn's learner only; empty: none)."""
    note: str = ""
    """Free text for readers."""

    def what(self) -> dict[str, Any]:
        """What decides the arm's numbers."""
        return {"learner": self.learner, "set": list(self.overrides), "preset": self.preset}


@dataclass(frozen=True)
class Protocol:
    """One way of evaluating: every arm's every seed, and every baseline, under it."""

    name: str
    """The protocol's name (evaluation folders: ``eval_NAME``)."""
    start: str = "stage"
    """``devlearn eval --start``: one of :data:`STARTS`."""
    episodes: int = 10
    """Episodes per evaluation."""
    seed: int = 0
    """Seed of the episodes' initial poses (the same for every arm: a paired comparison)."""
    action: str = "mean"
    """A trained policy's action: ``mean`` or ``sample`` (baselines act as they are named)."""
    overrides: tuple[str, ...] = ()
    """``devlearn eval --set`` items: a checkpoint takes only ``infant.age_months``."""
    session_s: float | None = None
    """``devlearn eval --session``: every episode one session of this many simulated seconds,
    without a reset inside (None: the behaviour's episodes); :attr:`episodes` counts sessions."""

    @property
    def folder(self) -> str:
        """The evaluation's folder in a run folder (and under a baseline's)."""
        return f"eval_{self.name}"

    def what(self) -> dict[str, Any]:
        """What decides the protocol's numbers (``session_s`` only where set, so that a folder
        started before the key existed keeps its protocols)."""
        what: dict[str, Any] = {
            "start": self.start,
            "episodes": self.episodes,
            "seed": self.seed,
            "action": self.action,
            "set": list(self.overrides),
        }
        if self.session_s is not None:
            what["session_s"] = self.session_s
        return what

    def describe(self) -> str:
        """One line for people: ``100 episodes from stage starts, eval seed 0, mean action``
        (``10 sessions of 300 s from rest starts, ...`` with :attr:`session_s`)."""
        played = (
            f"{self.episodes} episodes"
            if self.session_s is None
            else f"{self.episodes} sessions of {self.session_s:g} s"
        )
        text = f"{played} from {self.start} starts, eval seed {self.seed}, {self.action} action"
        return text + (f", {' '.join(self.overrides)}" if self.overrides else "")


@dataclass(frozen=True)
class ReferenceRow:
    """One published figure: its label, value and interval if given, and figures for other
    eval.json numbers (``experiment table --metric`` columns) by their dotted keys."""

    label: str
    value: float | None
    """The headline's figure; None where the source has only ``metrics`` (infants have no
    per-episode score)."""
    low: float | None = None
    high: float | None = None
    metrics: tuple[tuple[str, str], ...] = ()
    """``(dotted key, figure as the source gives it)``: a number or words such as ``<= 40``
    or ``~0.5`` (a source's figure is often a bound or an approximation, not a mean)."""


@dataclass(frozen=True)
class Reference:
    """Figures from elsewhere (the paper, an earlier result) shown beside a protocol's table."""

    source: str
    """Where the figures come from, in words (paper and table, a results README, a commit)."""
    protocol: str
    """The protocol whose table shows them."""
    rows: tuple[ReferenceRow, ...]
    """The figures."""
    note: str = ""
    """Free text for readers (how the figures were measured)."""


@dataclass
class TrainSettings:
    """Budget and settings of every run of every arm."""

    steps: int | None = None
    """Environment steps per run (None: the behaviour's default ``total_steps``)."""
    envs: int | None = None
    """Environments per run (None: the behaviour's default ``num_envs``)."""
    workers: int = 0
    """Env worker processes per run (fixed, so a run trains the same numbers anywhere)."""
    torch_threads: int | None = None
    """Torch threads per run (None: the cores a run holds)."""
    cores: int | None = None
    """Cores each run holds (None: ``max(1, workers)``)."""
    overrides: tuple[str, ...] = ()
    """``key=value`` overrides of every arm (before the arm's own)."""

    @property
    def cores_per_run(self) -> int:
        """The cores one run (or evaluation) holds."""
        return self.cores if self.cores is not None else max(1, self.workers)

    @property
    def threads(self) -> int:
        """The torch threads of a run."""
        return self.torch_threads if self.torch_threads is not None else self.cores_per_run

    def what(self) -> dict[str, Any]:
        """What decides every run's numbers."""
        return {
            "steps": self.steps,
            "envs": self.envs,
            "workers": self.workers,
            "torch_threads": self.threads,
            "set": list(self.overrides),
        }


@dataclass
class ExperimentSpec:
    """An experiment file, read and checked for shape."""

    path: Path
    """The file."""
    text: str
    """Its content (copied into the experiment's folder and its publication)."""
    name: str
    """The experiment's name."""
    behavior: str
    """The behaviour every arm trains."""
    arms: list[Arm]
    """The arms, in the file's order."""
    protocols: list[Protocol]
    """The evaluation protocols; the first one picks each arm's published policy."""
    seeds: list[int] = field(default_factory=lambda: [0])
    """Seeds of every arm."""
    baselines: list[str] = field(default_factory=list)
    """Baseline policies evaluated once per protocol."""
    baseline_overrides: tuple[str, ...] = ()
    """``devlearn eval --set`` items of every baseline's evaluation, after the protocol's: what
    a baseline needs that the arms' runs hold in their configs (hand regard's shared detector,
    ``behavior.detector_file``; a trained policy's evaluation takes its run's config)."""
    train: TrainSettings = field(default_factory=TrainSettings)
    """Budget and settings of every run."""
    references: list[Reference] = field(default_factory=list)
    """Figures from elsewhere, by protocol."""
    description: str = ""
    """Free text for readers."""
    executor: str = "local"
    """``local`` or ``ray``."""
    jobs: int | None = None
    """Local executor: runs at a time (None: as many as fit the cores)."""
    address: str | None = None
    """Ray executor: the cluster (None: a local instance)."""
    launcher: list[str] | None = None
    """The command that starts devlearn where a run executes (None: this Python)."""

    @property
    def sha256(self) -> str:
        """The file's digest (recorded at every start)."""
        return hashlib.sha256(self.text.encode()).hexdigest()

    def arm(self, name: str) -> Arm:
        """The arm named ``name``."""
        return next(a for a in self.arms if a.name == name)

    def what(self) -> dict[str, Any]:
        """The settings that decide the numbers; an experiment folder keeps them across starts
        (arms, protocols, seeds and baselines may be added)."""
        what: dict[str, Any] = {
            "behavior": self.behavior,
            "train": self.train.what(),
            "arms": {arm.name: arm.what() for arm in self.arms},
            "protocols": {p.name: p.what() for p in self.protocols},
        }
        if self.baseline_overrides:  # only where set: folders started before the key match
            what["baseline_set"] = list(self.baseline_overrides)
        return what


class _Checker:
    """Reads values out of the parsed file, each error one line naming the file and the key."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def error(self, where: str, message: str) -> UsageError:
        return UsageError(f"experiment file {self.path}: {where}: {message}")

    def keys(self, table: Any, section: str, where: str) -> dict[str, Any]:
        if not isinstance(table, dict):
            raise self.error(where, "must be a table")
        unknown = sorted(set(table) - KEYS[section])
        if unknown:
            raise self.error(
                where, f"unknown key '{unknown[0]}'; valid: {', '.join(sorted(KEYS[section]))}"
            )
        return table

    def text(self, value: Any, where: str, required: bool = False, default: str = "") -> str:
        if value is None:
            if required:
                raise self.error(where, "is required")
            return default
        if not isinstance(value, str) or (required and not value.strip()):
            raise self.error(where, f"must be a {'non-empty ' if required else ''}string")
        return value

    def name(self, value: Any, where: str) -> str:
        name = self.text(value, where, required=True)
        if not SAFE_NAME.fullmatch(name) or len(name) > NAME_MAX:
            raise self.error(
                where,
                f"'{name}' must be letters, digits and _ . + - (it names folders), starting with "
                f"a letter or digit, at most {NAME_MAX} characters",
            )
        return name

    def integer(self, value: Any, where: str, low: int, high: int, default: int) -> int:
        found = self.maybe_integer(value, where, low, high)
        return default if found is None else found

    def maybe_integer(self, value: Any, where: str, low: int, high: int) -> int | None:
        if value is None:
            return None
        wanted = f"must be an integer from {low} to {high:,}"
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(where, f"{wanted}, got {value!r}")
        if isinstance(value, float) and (not math.isfinite(value) or not value.is_integer()):
            raise self.error(where, f"{wanted}, got {value!r}")
        if not low <= value <= high:
            raise self.error(where, f"{wanted}, got {value:,}")
        return int(value)

    def number(self, value: Any, where: str, required: bool = False) -> float | None:
        if value is None and not required:
            return None
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(where, f"must be a number, got {value!r}")
        if not math.isfinite(value):
            raise self.error(where, f"must be a finite number, got {value!r}")
        return float(value)

    def choice(
        self, value: Any, where: str, valid: tuple[str, ...] | list[str], default: str
    ) -> str:
        if value is None:
            return default
        if value not in valid:
            raise self.error(where, f"unknown value {value!r}; valid: {', '.join(valid)}")
        return str(value)

    def overrides(self, value: Any, where: str) -> tuple[str, ...]:
        if value is None:
            return ()
        if isinstance(value, dict):
            return tuple(f"{k}={value_text(v)}" for k, v in value.items())
        if isinstance(value, list) and all(isinstance(v, str) and "=" in v for v in value):
            return tuple(value)
        raise self.error(
            where, "must be a table of key = value or a list of 'key=value' strings (as --set)"
        )

    def tables(self, value: Any, where: str, required: bool) -> list[dict[str, Any]]:
        if value is None:
            if required:
                raise self.error(where, f"is required: one or more [[{where}]] tables")
            return []
        if not isinstance(value, list) or not all(isinstance(t, dict) for t in value):
            raise self.error(where, f"must be a list of tables ([[{where}]])")
        if required and not value:
            raise self.error(where, f"is empty; give one or more [[{where}]] tables")
        return value

    def seeds(self, value: Any) -> list[int]:
        if value is None:
            return [0]
        if isinstance(value, str):
            try:
                return parse_seeds(value)
            except UsageError as exc:
                raise self.error("seeds", str(exc).replace("--seeds ", "")) from None
        if (
            isinstance(value, list)
            and value
            and all(isinstance(s, int) and not isinstance(s, bool) for s in value)
        ):
            if any(not 0 <= s <= SEED_MAX for s in value):
                raise self.error("seeds", f"must be from 0 to {SEED_MAX}, got {value}")
            if len(set(value)) != len(value):
                raise self.error("seeds", f"lists a seed twice: {value}")
            return list(value)
        raise self.error(
            "seeds", f"must be a list of integers or a range like '1-3', got {value!r}"
        )

    def unique(self, names: list[str], where: str) -> None:
        seen = set()
        for name in names:
            if name in seen:
                raise self.error(where, f"the name '{name}' is given twice")
            seen.add(name)


def _arm(check: _Checker, table: dict[str, Any], where: str) -> Arm:
    check.keys(table, "arms", where)
    name = check.name(table.get("name"), f"{where} name")
    where = f"arms '{name}'"
    if name.startswith("baseline_"):
        raise check.error(where, "an arm's name may not start with baseline_ (the baselines')")
    learner = check.choice(table.get("learner"), f"{where} learner", list(LEARNERS), "devlearn")
    preset = check.text(table.get("preset"), f"{where} preset")
    if preset and learner != "devlearn":
        raise check.error(
            f"{where} preset",
            f"a preset is devlearn's (devlearn run --preset); learner {learner} takes set only",
        )
    return Arm(
        name=name,
        learner=learner,
        overrides=check.overrides(table.get("set"), f"{where} set"),
        preset=preset,
        note=check.text(table.get("note"), f"{where} note"),
    )


def _protocol(check: _Checker, table: dict[str, Any], where: str) -> Protocol:
    check.keys(table, "protocols", where)
    name = check.name(table.get("name"), f"{where} name")
    where = f"protocols '{name}'"
    return Protocol(
        name=name,
        start=check.choice(table.get("start"), f"{where} start", STARTS, "stage"),
        episodes=check.integer(table.get("episodes"), f"{where} episodes", 1, EPISODES_MAX, 10),
        seed=check.integer(table.get("seed"), f"{where} seed", 0, SEED_MAX, 0),
        action=check.choice(table.get("action"), f"{where} action", ACTIONS, "mean"),
        overrides=check.overrides(table.get("set"), f"{where} set"),
        session_s=_session(check, table.get("session_s"), f"{where} session_s"),
    )


def _session(check: _Checker, value: Any, where: str) -> float | None:
    """A protocol's ``session_s``: seconds above 0, at most :data:`SESSION_S_MAX`, a whole
    number of BabyBench's physics steps (each arm's decisions are checked when planned)."""
    from devlearn.timing import physics_steps

    seconds = check.number(value, where)
    if seconds is None:
        return None
    if not 0 < seconds <= SESSION_S_MAX:
        raise check.error(
            where, f"must be above 0 and at most {SESSION_S_MAX:g} seconds, got {seconds:g}"
        )
    try:
        physics_steps(seconds)
    except ValueError as err:
        raise check.error(where, str(err)) from None
    return seconds


def _reference(
    check: _Checker, table: dict[str, Any], where: str, protocols: list[str]
) -> Reference:
    check.keys(table, "references", where)
    source = check.text(table.get("source"), f"{where} source", required=True)
    protocol = check.text(table.get("protocol"), f"{where} protocol", default=protocols[0])
    if protocol not in protocols:
        raise check.error(
            f"{where} protocol", f"unknown protocol '{protocol}'; valid: {', '.join(protocols)}"
        )
    rows = []
    for i, row in enumerate(check.tables(table.get("rows"), f"{where} rows", required=True)):
        at = f"{where} rows[{i}]"
        check.keys(row, "rows", at)
        low, high = (
            check.number(row.get("low"), f"{at} low"),
            check.number(row.get("high"), f"{at} high"),
        )
        if (low is None) != (high is None):
            raise check.error(at, "give both low and high (an interval), or neither")
        metrics = _reference_metrics(check, row.get("metrics"), f"{at} metrics")
        value = check.number(row.get("value"), f"{at} value", required=not metrics)
        label = check.text(row.get("label"), f"{at} label", True)
        rows.append(ReferenceRow(label, value, low, high, metrics))
    return Reference(source, protocol, tuple(rows), check.text(table.get("note"), f"{where} note"))


def _reference_metrics(check: _Checker, value: Any, where: str) -> tuple[tuple[str, str], ...]:
    """A reference row's ``metrics`` table: dotted eval.json keys to a number or short text."""
    if value is None:
        return ()
    if not isinstance(value, dict) or not value:
        raise check.error(
            where,
            "must be a table of eval.json keys to figures, e.g. "
            '{ "likeness_coded.touches_per_minute" = "<= 40" }',
        )
    figures = []
    for key, figure in value.items():
        if isinstance(figure, bool) or not isinstance(figure, (int, float, str)):
            raise check.error(f"{where}.{key}", f"must be a number or text, got {figure!r}")
        if isinstance(figure, str) and not figure.strip():
            raise check.error(f"{where}.{key}", "must not be empty")
        text = figure if isinstance(figure, str) else f"{float(figure):.4g}"
        figures.append((str(key), text))
    return tuple(figures)


def read_experiment(path: str | Path) -> ExperimentSpec:
    """Read an experiment file and check its shape: known keys only, the right kinds of
    values, names that can name folders, each name once.

    Args:
        path: A TOML experiment file.
    Returns:
        The experiment (its configs are resolved later, by :func:`plan_experiment
        <devlearn.experiment.plan.plan_experiment>`).
    Raises:
        UsageError: One line naming the file, the key and what is valid.
    """
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise UsageError(f"cannot read experiment file {path}: {exc.strerror or exc}") from None
    data = load_toml(path, "experiment file")
    check = _Checker(path)
    check.keys(data, "", "the top level")
    train = check.keys(data.get("train", {}), "train", "[train]")
    execution = check.keys(data.get("executor", {}), "executor", "[executor]")
    arms = [
        _arm(check, t, f"arms[{i}]")
        for i, t in enumerate(check.tables(data.get("arms"), "arms", True))
    ]
    check.unique([a.name for a in arms], "arms")
    protocols = [
        _protocol(check, t, f"protocols[{i}]")
        for i, t in enumerate(check.tables(data.get("protocols"), "protocols", True))
    ]
    check.unique([p.name for p in protocols], "protocols")
    names = [p.name for p in protocols]
    references = [
        _reference(check, t, f"references[{i}]", names)
        for i, t in enumerate(check.tables(data.get("references"), "references", False))
    ]
    baselines = data.get("baselines", [])
    if not isinstance(baselines, list):
        raise check.error("baselines", f"must be a list; valid items: {', '.join(BASELINES)}")
    for item in baselines:
        check.choice(item, "baselines", BASELINES, "")
    check.unique(list(baselines), "baselines")
    executor = check.choice(execution.get("kind"), "[executor] kind", EXECUTORS, "local")
    address = check.text(execution.get("address"), "[executor] address") or None
    if address and executor != "ray":
        raise check.error("[executor] address", 'is for kind = "ray"')
    launcher = execution.get("launcher")
    if launcher is not None and not (
        isinstance(launcher, list) and launcher and all(isinstance(v, str) for v in launcher)
    ):
        raise check.error("[executor] launcher", 'must name a command as a list, e.g. ["devlearn"]')
    return ExperimentSpec(
        path=path,
        text=text,
        name=check.name(data.get("name", path.stem), "name"),
        behavior=check.text(data.get("behavior"), "behavior", required=True),
        description=check.text(data.get("description"), "description"),
        arms=arms,
        protocols=protocols,
        seeds=check.seeds(data.get("seeds")),
        baselines=list(baselines),
        baseline_overrides=check.overrides(data.get("baseline_set"), "baseline_set"),
        train=TrainSettings(
            steps=check.maybe_integer(train.get("steps"), "[train] steps", 1, STEPS_MAX),
            envs=check.maybe_integer(train.get("envs"), "[train] envs", 1, ENVS_MAX),
            workers=check.integer(train.get("workers"), "[train] workers", 0, CORES_MAX, 0),
            torch_threads=check.maybe_integer(
                train.get("torch_threads"), "[train] torch_threads", 0, THREADS_MAX
            ),
            cores=check.maybe_integer(train.get("cores"), "[train] cores", 1, CORES_MAX),
            overrides=check.overrides(train.get("set"), "[train] set"),
        ),
        references=references,
        executor=executor,
        jobs=check.maybe_integer(execution.get("jobs"), "[executor] jobs", 1, CORES_MAX),
        address=address,
        launcher=None if launcher is None else list(launcher),
    )
