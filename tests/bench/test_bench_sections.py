"""``devlearn bench --only``: the sections it measures (no speed is asserted)."""

from __future__ import annotations

import pytest

from devlearn.api.errors import UsageError
from devlearn.bench import run as bench_run
from devlearn.cli.commands import COMMANDS
from devlearn.testing import registry_for
from devlearn.testing.fake_infant import TinyBehavior


@pytest.fixture()
def called(monkeypatch):
    """Replace every section's measurement with one that records its name."""
    names: list[str] = []

    def recorder(name):
        def measure(registry, quick, progress):
            names.append(name)
            return {f"{name}_figure": 1.0}

        return measure

    sections = {name: (recorder(name), needs) for name, (_, needs) in bench_run.SECTIONS.items()}
    monkeypatch.setattr(bench_run, "SECTIONS", sections)
    return names


def test_only_the_named_sections_run_in_the_benchs_order(called):
    registry = registry_for(TinyBehavior)
    result = bench_run.run_bench(
        registry, quick=True, progress=lambda m: None, only=("learner", "startup")
    )
    assert called == ["startup", "learner"]
    assert result["startup_figure"] == 1.0 and result["sections"] == ["learner", "startup"]
    assert "machine" in result and "peak_memory_mb" in result


def test_a_section_whose_behaviour_is_missing_is_skipped_and_said(called):
    said: list[str] = []
    bench_run.run_bench(registry_for(TinyBehavior), True, said.append, only=("cnn", "gym"))
    assert called == []
    assert said == [
        "gym: self_touch not installed, skipped",
        "cnn: hand_regard not installed, skipped",
    ]


def test_an_unknown_section_is_refused_with_the_valid_ones(called):
    with pytest.raises(UsageError, match="unknown bench section.*nope; valid: startup, infant"):
        bench_run.run_bench(registry_for(TinyBehavior), True, print, only=("startup", "nope"))
    assert called == []


def test_the_help_lists_every_section():
    bench = next(c for c in COMMANDS if c.name == "bench")
    only = next(o for o in bench.options if o.flags[0] == "--only")
    listed = only.kwargs["help"].rsplit(":", 1)[1]
    assert [name.strip() for name in listed.split(",")] == list(bench_run.SECTIONS)
