"""Issue #59: a contract you can hold in your head. ``Behavior`` has at most 12 public members,
and nothing in devlearn or the plugins chooses a path by checking which of its methods a class
overrides (the optional capabilities are composed objects instead)."""

from __future__ import annotations

import re
from pathlib import Path

from devlearn.api.behavior import Behavior

ROOT = Path(__file__).resolve().parents[2]

MEMBERS = {
    "name",
    "scene",
    "config_class",
    "about",
    "facts",
    "observe",
    "network",
    "reward_terms",
    "curriculum",
    "episode",
    "evaluation",
    "artifacts",
}
"""The contract, as the class declares it (``Behavior``'s docstring has a line for each)."""


def public_members(cls: type) -> set[str]:
    """Every public method and attribute ``cls`` itself defines (assigned or annotated, class
    variables included)."""
    declared = set(vars(cls)) | set(vars(cls).get("__annotations__", {}))
    return {name for name in declared if not name.startswith("_")}


def test_behavior_has_at_most_twelve_members():
    members = public_members(Behavior)
    assert len(members) <= 12, sorted(members)
    assert members == MEMBERS


def test_every_member_is_in_the_class_docstring():
    doc = Behavior.__doc__ or ""
    assert all(f"``{name}``" in doc for name in MEMBERS)


OVERRIDE_PROBE = re.compile(r"(?<![\w.])overrides\((?!self\b)|is not getattr\(Behavior,")
"""A bare ``overrides(...)`` function, defined or called (the probe ``env/batch_advance.py``
had; a method of that name, ``def overrides(self, ...)``, is something else), or a comparison of
a class's method with ``Behavior``'s: how a core picks a path by what a behaviour overrides."""


def test_nothing_probes_which_behavior_methods_a_class_overrides():
    sources = [*(ROOT / "devlearn").rglob("*.py"), *(ROOT / "plugins").rglob("*.py")]
    found = [
        f"{path.relative_to(ROOT)}:{number}: {line.strip()}"
        for path in sources
        for number, line in enumerate(path.read_text().splitlines(), 1)
        if OVERRIDE_PROBE.search(line)
    ]
    assert found == []
