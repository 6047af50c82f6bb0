"""What a sweep runs: the grid, seeds, training budget and evaluation, from options or a file."""

from __future__ import annotations

import itertools
import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from devlearn.api.errors import UsageError
from devlearn.config.checks import SEED_MAX

RESERVED_KEYS = {
    "seed": "--seeds",
    "total_steps": "--steps",
    "workers": "--workers",
    "out_dir": "--out",
    "behavior_name": "the BEHAVIOR argument",
}
"""Config keys a grid may not vary, and the sweep option that sets each instead."""

_UNSAFE = re.compile(r"[^A-Za-z0-9._+-]")


@dataclass
class TrainSpec:
    """The training budget and settings shared by every run of a sweep."""

    steps: int | None = None
    """Environment steps per run (None: the behaviour's default ``total_steps``)."""
    envs: int | None = None
    """Environments per run (None: the behaviour's default ``num_envs``)."""
    workers: int = 0
    """Environment worker processes per run (0: in the training process). Fixed, not
    automatic, so that a run trains the same numbers on any machine (docs/scaling.md)."""
    cores: int | None = None
    """CPU cores each run holds (None: ``max(1, workers)``); the local executor runs as many
    runs at a time as fit the machine's cores, Ray reserves this many CPUs per task."""
    overrides: list[str] = field(default_factory=list)
    """``key=value`` config overrides of every run (``--set``), before the grid's values."""
    preset: str = ""
    """The behaviour preset every run starts from (``--preset``, e.g. ``paper``; empty: none),
    under ``steps``, ``envs``, the overrides and the grid."""

    @property
    def cores_per_run(self) -> int:
        """The cores one run holds."""
        return self.cores if self.cores is not None else max(1, self.workers)


@dataclass
class EvalSpec:
    """How each trained run is evaluated (``devlearn eval`` on its final checkpoint)."""

    episodes: int = 10
    """Deterministic evaluation episodes per run."""
    seed: int = 0
    """Seed of the evaluation's initial poses (the same for every run: a paired comparison)."""
    args: list[str] = field(default_factory=list)
    """Further ``devlearn eval`` arguments for every run (e.g. protocol options)."""


@dataclass
class SweepSpec:
    """One experiment: every combination of grid values times seeds, trained and evaluated."""

    behavior: str
    """The behaviour every run trains."""
    out: Path
    """The sweep folder (runs/, records/, logs/, report/, sweep.json)."""
    grid: dict[str, list[str]] = field(default_factory=dict)
    """Config key -> the values to try, in order (strings as given to ``--set``)."""
    seeds: list[int] = field(default_factory=lambda: [0])
    """Seeds of every combination."""
    train: TrainSpec = field(default_factory=TrainSpec)
    """Training budget and shared settings."""
    evaluation: EvalSpec = field(default_factory=EvalSpec)
    """Evaluation of each run."""
    executor: str = "local"
    """``local`` (this machine) or ``ray`` (a Ray cluster, or a local Ray instance)."""
    jobs: int | None = None
    """Local executor: runs at a time (None: as many as fit the cores)."""
    address: str | None = None
    """Ray executor: ``auto``, ``HOST:PORT`` or ``ray://HOST:PORT`` (None: a local instance)."""
    launcher: list[str] | None = None
    """The command that starts devlearn where a run executes (None: that process's own Python
    with ``-m devlearn.cli``), e.g. a container wrapper on a cluster."""
    report: bool = True
    """Write ``devlearn report`` over the evaluated runs at the end."""

    def what(self) -> dict[str, Any]:
        """The settings that decide a run's numbers (a restarted sweep must keep them)."""
        return {
            "behavior": self.behavior,
            "train": {
                "steps": self.train.steps,
                "envs": self.train.envs,
                "workers": self.train.workers,
                "overrides": list(self.train.overrides),
                **({"preset": self.train.preset} if self.train.preset else {}),
            },
            "eval": {
                "episodes": self.evaluation.episodes,
                "seed": self.evaluation.seed,
                "args": list(self.evaluation.args),
            },
        }


@dataclass(frozen=True)
class Variant:
    """One run of the sweep: grid values and a seed."""

    values: tuple[tuple[str, str], ...]
    """(config key, value) pairs of the grid, in the grid's order."""
    seed: int
    """The run's seed."""
    name: str
    """Folder name, from the values: ``curriculum=fixed_only,seed=1``."""

    @property
    def overrides(self) -> list[str]:
        """The grid's values as ``key=value`` overrides."""
        return [f"{key}={value}" for key, value in self.values]


def value_text(value: Any) -> str:
    """A grid or override value (from a sweep file) as the text ``--set`` takes."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, dict)):
        return json.dumps(value)
    return str(value)


def parse_grid(items: list[str]) -> dict[str, list[str]]:
    """Parse ``--grid key=v1,v2`` options into {key: [values]} (UsageError naming the item)."""
    grid: dict[str, list[str]] = {}
    for text in items:
        key, sep, values = text.partition("=")
        key = key.strip()
        if not sep or not key:
            raise UsageError(
                f"--grid '{text}' must look like KEY=V1,V2 (e.g. behavior.curriculum=a,b)"
            )
        if key in grid:
            raise UsageError(f"--grid key '{key}' is given twice; list all its values once")
        grid[key] = [v.strip() for v in values.split(",")]
    return grid


SEEDS_MAX = 10_000
"""Most seeds one sweep lists (each is a run; beyond this a typo, not an experiment)."""


def parse_seeds(text: str) -> list[int]:
    """``1,2,3`` or ``1-5`` (or both: ``1-3,7``) -> a list of distinct seeds >= 0."""
    seeds: list[int] = []
    for part in text.split(","):
        part = part.strip()
        match = re.fullmatch(r"(\d+)(?:-(\d+))?", part)
        if not match or (match.group(2) and int(match.group(2)) < int(match.group(1))):
            raise UsageError(
                f"--seeds must be seeds >= 0 separated by commas, or ranges (e.g. 1,2,3 or "
                f"1-5), got '{text}'"
            )
        low, high = int(match.group(1)), int(match.group(2) or match.group(1))
        if len(seeds) + high - low + 1 > SEEDS_MAX:
            raise UsageError(f"--seeds '{text}' lists more than {SEEDS_MAX:,} seeds")
        if high > SEED_MAX:
            raise UsageError(f"--seeds must be at most {SEED_MAX}, got {high}")
        seeds += range(low, high + 1)
    if len(set(seeds)) != len(seeds):
        raise UsageError(f"--seeds lists a seed twice: '{text}'")
    return seeds


RUNS_MAX = 10_000
"""Most runs one sweep holds, grid combinations times seeds (as for :data:`SEEDS_MAX`: beyond
this a typo, not an experiment; a 3000 x 3000 grid planned for hours before printing one)."""


def check_size(grid: dict[str, list[str]], seeds: list[int]) -> int:
    """The number of runs of ``grid`` times ``seeds``, counted without listing them.

    Raises:
        UsageError: More than :data:`RUNS_MAX` (each factor named).
    """
    runs = len(seeds) * math.prod(len(values) for values in grid.values())
    if runs > RUNS_MAX:
        factors = [f"{len(values):,} values of {key}" for key, values in grid.items()]
        factors.append(f"{len(seeds):,} seed{'s' if len(seeds) != 1 else ''}")
        raise UsageError(
            f"the sweep would train {runs:,} runs ({' x '.join(factors)}), more than "
            f"{RUNS_MAX:,}; give fewer grid values or seeds, or split it into several sweeps"
        )
    return runs


def check_grid(grid: dict[str, list[str]], overrides: list[str]) -> None:
    """Reject empty or repeated values, reserved keys and keys also fixed by ``--set``."""
    fixed = {item.partition("=")[0].strip() for item in overrides}
    for key, values in grid.items():
        if key in RESERVED_KEYS:
            raise UsageError(f"--grid cannot vary '{key}'; use {RESERVED_KEYS[key]}")
        if key in fixed:
            raise UsageError(f"'{key}' is both in --grid and in --set; keep one")
        if not values or any(not v for v in values):
            raise UsageError(f"--grid {key} has an empty value: {','.join(values)!r}")
        if len(set(values)) != len(values):
            raise UsageError(f"--grid {key} lists a value twice: {','.join(values)}")


def _short_keys(keys: list[str]) -> dict[str, str]:
    """The last part of each dotted key, or the whole key where two keys share a last part."""
    last = [k.rsplit(".", 1)[-1] for k in keys]
    return {k: (s if last.count(s) == 1 and s != "seed" else k) for k, s in zip(keys, last)}


def variants(grid: dict[str, list[str]], seeds: list[int]) -> list[Variant]:
    """Every combination, seeds outermost: all variants of the first seed come first, so a
    sweep stopped early still holds a complete comparison.

    Raises:
        UsageError: More than :data:`RUNS_MAX` runs (:func:`check_size`), or two runs that
            would share a folder name.
    """
    check_size(grid, seeds)
    keys = list(grid)
    short = _short_keys(keys)
    result: list = []
    names: dict = {}
    for seed in seeds:
        for combo in itertools.product(*(grid[k] for k in keys)):
            parts = [f"{short[k]}={_UNSAFE.sub('_', v)}" for k, v in zip(keys, combo)]
            name = ",".join([*parts, f"seed={seed}"])
            values = tuple(zip(keys, combo))
            if name in names:
                raise UsageError(
                    f"grid values {dict(names[name])} and {dict(values)} give the same run "
                    f"folder name '{name}'; make the values differ in letters or digits"
                )
            names[name] = values
            result.append(Variant(values, seed, name))
    return result
