"""``infant.age_months`` and ``infant.growth`` (issue #41): documented keys, schedules, and
one-line errors naming what is valid."""

from __future__ import annotations

import json

import pytest

from devlearn.api.errors import UsageError
from devlearn.cli import main
from devlearn.config.checks import check_config
from devlearn.config.growth import GROWTH_PIECES, parse_growth, start_age
from devlearn.config.run_config import from_dict
from devlearn.testing import run_config
from devlearn.testing.fake_infant import TinyBehavior


def config(*overrides: str, total_steps: int = 24_000):
    cfg = run_config(TinyBehavior, list(overrides), total_steps=total_steps)
    check_config(cfg)
    return cfg


def test_a_range_schedule_goes_from_the_first_age_to_the_last_in_pieces():
    schedule = parse_growth("6->18", 0, 24_000)
    assert schedule is not None and len(schedule.ages) == GROWTH_PIECES
    assert schedule.ages[0] == 6.0 and schedule.ages[-1] == 18.0
    assert schedule.age_at(0, 24_000) == 6.0
    assert schedule.age_at(999, 24_000) == 6.0  # the first piece: 1,000 steps
    assert schedule.age_at(1000, 24_000) == pytest.approx(6 + 12 / 23)
    assert schedule.age_at(23_999, 24_000) == 18.0
    assert schedule.age_at(30_000, 24_000) == 18.0  # trained on: the last age
    every = parse_growth(" 6 -> 18 ", 6_000, 24_000)  # pieces of 6,000 steps: 4
    assert every is not None and every.ages == (6.0, 10.0, 14.0, 18.0)
    shrink = parse_growth("12->0", 12_000, 24_000)  # any direction, at least two pieces
    assert shrink is not None and shrink.ages == (12.0, 0.0)


def test_a_list_schedule_cuts_the_run_into_equal_parts():
    schedule = parse_growth("6,12,18", 0, 3_000)
    assert schedule is not None
    assert [schedule.age_at(s, 3_000) for s in (0, 999, 1000, 1999, 2000, 2999)] == [
        6.0,
        6.0,
        12.0,
        12.0,
        18.0,
        18.0,
    ]
    assert parse_growth("", 0, 3_000) is None and parse_growth("  ", 0, 3_000) is None


def test_a_stage_schedule_gives_each_curriculum_stage_its_age():
    schedule = parse_growth("stages:6, 18", 0, 3_000)
    assert schedule is not None and schedule.by_stage and schedule.ages == (6.0, 18.0)
    assert [schedule.age_at(0, 3_000, stage) for stage in (0, 1, 2)] == [6.0, 18.0, 18.0]
    assert schedule.age_at(2_999, 3_000) == 6.0  # the steps alone do not move it


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (["infant.age_months=25"], "infant.age_months must be between 0 and 24 months, got 25"),
        (["infant.age_months=-1"], "infant.age_months must be between 0 and 24 months"),
        (["infant.growth=6->30"], "infant.growth '6->30': its ages must be between 0 and 24"),
        (["infant.growth=six->18"], "infant.growth 'six->18' is not a schedule; valid: ''"),
        (["infant.growth=6-18"], "is not a schedule; valid: '' (none), 'A->B'"),
        (["infant.growth=6,,18"], "is not a schedule"),
        (["infant.growth=stages:6->18"], "is not a schedule; valid: '' (none), 'A->B'"),
        (["infant.growth=stages:6,25"], "its ages must be between 0 and 24 months, got 25"),
        (["infant.growth_every=-5"], "infant.growth_every must be at least 0"),
        (
            ["infant.growth=6->18", "infant.age_months=6"],
            "infant.age_months and infant.growth exclude each other",
        ),
    ],
)
def test_bad_ages_and_schedules_are_one_line_errors(overrides, message):
    with pytest.raises(UsageError) as err:
        config(*overrides)
    assert message in str(err.value) and "\n" not in str(err.value)


def test_the_age_a_run_starts_at():
    assert start_age(config()) is None  # the default body
    assert start_age(config("infant.age_months=9")) == 9.0
    grow = config("infant.growth=6,12")
    assert (start_age(grow), start_age(grow, 12_000)) == (6.0, 12.0)


def test_a_config_saved_before_ages_loads_as_the_default_body():
    saved = json.loads(json.dumps({"behavior_name": "tiny", "total_steps": 64}))
    cfg = from_dict(saved, TinyBehavior)
    assert (cfg.infant.age_months, cfg.infant.growth, cfg.infant.growth_every) == (None, "", 0)


def test_devlearn_config_documents_the_keys(capsys):
    assert main(["config", "self_touch", "--json"]) == 0
    rows = {r["key"]: r for r in json.loads(capsys.readouterr().out)}
    assert rows["infant.age_months"]["default"] is None
    assert "0 to 24 months" in rows["infant.age_months"]["doc"]
    assert "18-month-old" in rows["infant.age_months"]["doc"]  # the default body, named
    assert "6->18" in rows["infant.growth"]["doc"] and rows["infant.growth"]["default"] == ""
    assert rows["infant.growth_every"]["type"] == "int"
