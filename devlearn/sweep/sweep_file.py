"""Sweep files (TOML) and command-line options, merged into one SweepSpec.

A sweep file holds the same settings as ``devlearn sweep``'s options; an option given on the
command line wins over the file::

    behavior = "self_touch"
    out = "sweeps/curriculum"
    seeds = [1, 2, 3]

    [grid]
    "behavior.curriculum" = ["fixed_only", "random_only", "two_stage"]

    [train]
    steps = 400_000
    envs = 16
    workers = 0
    set = { "behavior.fixed_pose_steps" = 200_000 }

    [eval]
    episodes = 100
    seed = 0

    [executor]
    kind = "local"   # or "ray"
    jobs = 2         # local: runs at a time
"""

from __future__ import annotations

import sys
from pathlib import Path
from types import ModuleType
from typing import Any

from devlearn.api.errors import UsageError
from devlearn.api.json_files import read_text
from devlearn.config.checks import ENVS_MAX, SEED_MAX, STEPS_MAX
from devlearn.sweep.spec import (
    EvalSpec,
    SweepSpec,
    TrainSpec,
    check_grid,
    check_size,
    parse_grid,
    parse_seeds,
    value_text,
)

SECTIONS = {
    "": {"behavior", "out", "seeds", "grid", "train", "eval", "executor", "report"},
    "train": {"steps", "envs", "workers", "cores", "set", "preset"},
    "eval": {"episodes", "seed", "args"},
    "executor": {"kind", "jobs", "address", "launcher"},
}
"""Valid keys of a sweep file, per table ("" is the top level)."""
EXECUTORS = ("local", "ray")


def _toml() -> ModuleType:
    if sys.version_info >= (3, 11):
        import tomllib

        return tomllib
    try:
        import tomli
    except ModuleNotFoundError:
        raise UsageError("sweep files need Python 3.11+ or the tomli package") from None
    return tomli


def load_toml(path: Path, what: str = "sweep file") -> dict[str, Any]:
    """The tables of a TOML file; UsageError (naming ``what`` and the file) when it cannot be
    read or is not TOML."""
    text = read_text(path)  # the guarded reader's: a regular file, of a bounded size
    try:
        return dict(_toml().loads(text))
    except ValueError as exc:  # tomllib.TOMLDecodeError
        raise UsageError(f"{what} {path} is not valid TOML: {exc}") from None
    except RecursionError:
        raise UsageError(f"{what} {path} is nested too deeply") from None


def read_sweep_file(path: str | Path) -> dict[str, Any]:
    """Read and check a TOML sweep file: known keys only, the right kinds of values."""
    path = Path(path)
    data = load_toml(path)
    for section, keys in SECTIONS.items():
        table = data if not section else data.get(section, {})
        if not isinstance(table, dict):
            raise UsageError(f"sweep file {path}: [{section}] must be a table")
        unknown = sorted(set(table) - keys)
        if unknown:
            where = f"[{section}]" if section else "the top level"
            raise UsageError(
                f"sweep file {path}: unknown key '{unknown[0]}' in {where}; "
                f"valid: {', '.join(sorted(keys))}"
            )
    grid = data.get("grid", {})
    if not isinstance(grid, dict) or not all(isinstance(v, list) for v in grid.values()):
        raise UsageError(f"sweep file {path}: [grid] maps each config key to a list of values")
    return data


def _integer(value: Any, option: str, minimum: int, maximum: int = 4_096) -> int:
    try:
        number = float(value)
        if not number.is_integer():
            raise ValueError
    except (TypeError, ValueError, OverflowError):
        raise UsageError(f"{option} must be an integer, got '{value}'") from None
    if number < minimum:
        raise UsageError(f"{option} must be at least {minimum}, got {int(number)}")
    if number > maximum:
        raise UsageError(f"{option} must be at most {maximum:g}, got {number:g}")
    return int(number)


def _overrides(value: Any, option: str) -> list[str]:
    if isinstance(value, dict):
        return [f"{k}={value_text(v)}" for k, v in value.items()]
    if isinstance(value, list) and all(isinstance(v, str) for v in value):
        return list(value)
    raise UsageError(f"{option} must be a table of key = value or a list of 'key=value'")


def _strings(value: Any, option: str) -> list[str]:
    if isinstance(value, list) and all(isinstance(v, str) for v in value):
        return list(value)
    raise UsageError(f"{option} must be a list of strings")


def build_spec(behavior: str, options: dict[str, Any], file: str | Path | None) -> SweepSpec:
    """Merge a sweep file (optional) and command-line options (None where not given).

    Args:
        behavior: The BEHAVIOR argument.
        options: ``out``, ``grid`` (list of KEY=V1,V2), ``seeds`` (text), ``steps``, ``envs``,
            ``workers``, ``cores``, ``overrides`` (list of key=value), ``preset``, ``episodes``,
            ``eval_seed``, ``eval_args``, ``executor``, ``jobs``, ``address``, ``report``.
        file: A TOML sweep file.
    Raises:
        UsageError: Anything that does not parse, with what is valid.
    """
    data = read_sweep_file(file) if file else {}
    if data.get("behavior", behavior) != behavior:
        raise UsageError(
            f"sweep file {file} is for behavior '{data['behavior']}', not '{behavior}'"
        )
    train, evaluation = data.get("train", {}), data.get("eval", {})
    execution = data.get("executor", {})

    def pick(option: str, table: dict, key: str, default: Any = None) -> Any:
        value = options.get(option)
        return value if value is not None else table.get(key, default)

    grid = {k: [value_text(v) for v in values] for k, values in data.get("grid", {}).items()}
    grid.update(parse_grid(options.get("grid") or []))  # a key on the command line wins
    seeds_value = options.get("seeds")
    if seeds_value is None:
        seeds_value = data.get("seeds", [0])
    if isinstance(seeds_value, str):
        seeds = parse_seeds(seeds_value)
    elif isinstance(seeds_value, list) and all(isinstance(s, int) for s in seeds_value):
        seeds = parse_seeds(",".join(str(s) for s in seeds_value))
    else:
        raise UsageError(f"seeds must be a list of integers, got {seeds_value!r}")
    out = pick("out", data, "out")
    if not out:
        raise UsageError('a sweep needs its folder: --out DIR (or out = "DIR" in the file)')
    steps, envs = pick("steps", train, "steps"), pick("envs", train, "envs")
    cores = pick("cores", train, "cores")
    overrides = _overrides(train.get("set", []), "[train] set") + list(
        options.get("overrides") or []
    )
    check_grid(grid, overrides)
    check_size(grid, seeds)  # before any run is planned: each is a config resolved
    executor = pick("executor", execution, "kind", "local")
    if executor not in EXECUTORS:
        raise UsageError(f"unknown executor '{executor}'; valid: {', '.join(EXECUTORS)}")
    jobs, address = pick("jobs", execution, "jobs"), pick("address", execution, "address")
    if executor == "local" and address is not None:
        raise UsageError("--address is for --executor ray")
    launcher = execution.get("launcher")
    report = options.get("report")
    spec = SweepSpec(
        behavior=behavior,
        out=Path(out),
        grid=grid,
        seeds=seeds,
        train=TrainSpec(
            steps=None if steps is None else _integer(steps, "--steps", 1, STEPS_MAX),
            envs=None if envs is None else _integer(envs, "--envs", 1, ENVS_MAX),
            workers=_integer(pick("workers", train, "workers", 0), "--workers", 0),
            cores=None if cores is None else _integer(cores, "--cores", 1),
            overrides=overrides,
            preset=str(pick("preset", train, "preset", "") or ""),
        ),
        evaluation=EvalSpec(
            episodes=_integer(
                pick("episodes", evaluation, "episodes", 10), "--episodes", 1, 1_000_000
            ),
            seed=_integer(pick("eval_seed", evaluation, "seed", 0), "--eval-seed", 0, SEED_MAX),
            args=_strings(pick("eval_args", evaluation, "args", []), "eval args"),
        ),
        executor=executor,
        jobs=None if jobs is None else _integer(jobs, "--jobs", 1),
        address=None if address is None else str(address),
        launcher=None if launcher is None else _strings(launcher, "[executor] launcher"),
        report=bool(data.get("report", True)) if report is None else bool(report),
    )
    if spec.launcher is not None and not spec.launcher:
        raise UsageError('[executor] launcher must name a command, e.g. ["devlearn"]')
    return spec
