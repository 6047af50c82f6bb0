"""Growth schedules: the infant's age over a run (``infant.growth``, issue #41)."""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass
from typing import TYPE_CHECKING

from devlearn.ages import check_age
from devlearn.api.errors import UsageError

if TYPE_CHECKING:
    from devlearn.config.run_config import RunConfig

GROWTH_PIECES = 24
"""Pieces of a run an ``A->B`` schedule is cut into when ``infant.growth_every`` is 0: half a
month each for 6 -> 18 months, each piece's rebuild well under a second per env worker."""

GROWTH_FORMS = (
    "'' (none), 'A->B' (A months at the start to B at the end, in pieces of "
    "infant.growth_every steps), 'A,B,...' (the run in equal parts at these ages), "
    "'stages:A,B,...' (one age per curriculum stage)"
)
"""The schedules ``infant.growth`` takes, as its errors list them."""

_RANGE = re.compile(r"^\s*([^,>]+?)\s*->\s*([^,>]+?)\s*$")


@dataclass(frozen=True)
class GrowthSchedule:
    """The body's age over a run: the run cut into equal pieces, one age each, or one age per
    curriculum stage.

    Attributes:
        ages: The age (months) of each piece (or stage), in order.
        by_stage: One age per curriculum stage (the last age for any later stage).
        steps: The steps the pieces span (``infant.growth_steps``); 0: the run's.
    """

    ages: tuple[float, ...]
    by_stage: bool = False
    steps: int = 0

    def age_at(self, env_steps: int, total_steps: int, stage: int = 0) -> float:
        """The age at ``env_steps`` environment steps of a ``total_steps`` run (the last
        piece's from the end of the schedule's :attr:`steps`, or of the run, on), or in
        curriculum stage ``stage`` (index from 0)."""
        if self.by_stage:
            piece = stage
        else:
            span = self.steps or int(total_steps)
            piece = int(env_steps) * len(self.ages) // max(span, 1)
        return self.ages[min(piece, len(self.ages) - 1)]


def _age(text: str, schedule: str) -> float:
    try:
        return check_age(float(text), "its ages")
    except ValueError as err:
        if "months" in str(err):
            raise UsageError(f"infant.growth '{schedule}': {err}") from None
        raise UsageError(
            f"infant.growth '{schedule}' is not a schedule; valid: {GROWTH_FORMS}"
        ) from None


def parse_growth(schedule: str, every: int, total_steps: int) -> GrowthSchedule | None:
    """The schedule ``infant.growth`` names (None for ''), for a run of ``total_steps``.

    ``A->B``: the run in pieces of ``every`` steps (0: :data:`GROWTH_PIECES` pieces), the
    first at A months, the last at B, evenly between; ``A,B,...``: equal parts at those ages;
    ``stages:A,B,...``: the behaviour's curriculum stages at those ages. The runner gives the
    envs a piece's (or stage's) age at the first iteration boundary inside it.

    Raises:
        UsageError: One line: not one of :data:`GROWTH_FORMS`, or an age outside 0-24 months.
    """
    if not schedule.strip():
        return None
    by_stage = schedule.strip().startswith("stages:")
    if by_stage:
        ages = schedule.strip().removeprefix("stages:")
        if "->" in ages:
            raise UsageError(f"infant.growth '{schedule}' is not a schedule; valid: {GROWTH_FORMS}")
        return GrowthSchedule(tuple(_age(part, schedule) for part in ages.split(",")), True)
    found = _RANGE.match(schedule)
    if found:
        start, end = _age(found.group(1), schedule), _age(found.group(2), schedule)
        pieces = GROWTH_PIECES if every <= 0 else max(2, math.ceil(total_steps / every))
        return GrowthSchedule(
            tuple(start + (end - start) * k / (pieces - 1) for k in range(pieces))
        )
    if ">" in schedule or "-" in schedule.replace("->", ""):
        raise UsageError(f"infant.growth '{schedule}' is not a schedule; valid: {GROWTH_FORMS}")
    return GrowthSchedule(tuple(_age(part, schedule) for part in schedule.split(",")))


def growth_schedule(cfg: RunConfig) -> GrowthSchedule | None:
    """The run's growth schedule (None: its body keeps ``infant.age_months``).

    Raises:
        UsageError: A bad schedule, or one given together with ``infant.age_months``.
    """
    span = cfg.infant.growth_steps or cfg.total_steps
    schedule = parse_growth(cfg.infant.growth, cfg.infant.growth_every, span)
    if schedule is not None:
        schedule = dataclasses.replace(schedule, steps=span)
    if schedule is not None and cfg.infant.age_months is not None:
        raise UsageError(
            "infant.age_months and infant.growth exclude each other (a growing body's age "
            "comes from its schedule); set one of them"
        )
    return schedule


GROWTH_KEYS = ("growth", "growth_every", "growth_steps")
"""The ``infant`` fields that make a growth schedule: what a resumed run keeps."""


def keep_growth_on_resume(saved: RunConfig, resumed: RunConfig, run: str) -> str | None:
    """Check a resumed run's growth schedule against its saved one, in place: the schedule a
    run grew by is the one it goes on with, so that the body's age never goes back (a
    schedule over another ``--steps`` gave 14 months where the run had reached 18).

    A changed ``infant.growth``, ``growth_every`` or ``growth_steps`` is refused. With another
    ``total_steps`` the schedule keeps the steps it spanned: ``resumed.infant.growth_steps`` is
    set to them (recorded in config.json, so later resumes keep them too).

    Returns:
        A note saying so when the span was fixed here (None otherwise).
    Raises:
        UsageError: A growth key changed (the saved and the new values named, and how to grow
            otherwise: a new run from the checkpoint).
    """
    for key in GROWTH_KEYS:
        before, after = getattr(saved.infant, key), getattr(resumed.infant, key)
        if before != after:
            raise UsageError(
                f"run {run} grows by infant.{key}={before!r}, which a resumed run keeps (its "
                f"body's age goes on from its step), not {after!r}; for another schedule start "
                f"a new run from its checkpoint: --from {run}/checkpoint_latest.pt --out NEW_DIR"
            )
    schedule = growth_schedule(saved)
    if schedule is None or schedule.by_stage or saved.infant.growth_steps:
        return None  # by stage, or already fixed: the steps change no age
    if resumed.total_steps == saved.total_steps:
        return None
    resumed.infant.growth_steps = saved.total_steps
    last = growth_schedule(resumed)
    assert last is not None
    return (
        f"run {run} keeps its growth schedule over its first {saved.total_steps:,} steps "
        f"(infant.growth_steps, recorded in config.json); its body stays at "
        f"{last.ages[-1]:g} months after them"
    )


def start_age(cfg: RunConfig, env_steps: int = 0, stage: int = 0) -> float | None:
    """The body's age at ``env_steps`` of the run, in curriculum stage ``stage``: the
    schedule's, else ``infant.age_months`` (None: the default body)."""
    schedule = growth_schedule(cfg)
    if schedule is None:
        return cfg.infant.age_months
    return schedule.age_at(env_steps, cfg.total_steps, stage)
