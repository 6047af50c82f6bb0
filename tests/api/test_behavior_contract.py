"""The Behavior contract: a small core every behaviour writes, and optional capabilities in
groups, each declared with a default (never found by ``hasattr``)."""

from __future__ import annotations

import inspect
import re
from pathlib import Path

import devlearn
from devlearn.api.behavior import BEHAVIOR_CORE, BEHAVIOR_OPTIONAL, Behavior, Evaluator
from devlearn.testing import TinyBehavior


def public_members(cls: type) -> set[str]:
    """Every public attribute and method ``cls`` declares (annotated or assigned)."""
    declared = set(vars(cls)) | set(vars(cls).get("__annotations__", {}))
    return {n for n in declared if not n.startswith("_")}


def test_every_public_member_is_core_or_in_one_optional_group():
    optional = [name for group in BEHAVIOR_OPTIONAL.values() for name in group]
    listed = [*BEHAVIOR_CORE, *optional]
    assert len(listed) == len(set(listed))  # once each
    assert set(listed) == public_members(Behavior)


def test_the_core_is_at_most_six_methods_two_of_them_abstract():
    methods = [n for n in BEHAVIOR_CORE if callable(getattr(Behavior, n, None))]
    assert len(methods) <= 6
    assert Behavior.__abstractmethods__ == {"observe", "network"}
    assert set(BEHAVIOR_CORE) - set(methods) == {"name", "scene", "config_class"}


def test_every_optional_member_has_a_default():
    behavior = TinyBehavior()
    for group, names in BEHAVIOR_OPTIONAL.items():
        for name in names:
            assert name not in Behavior.__abstractmethods__, (group, name)
            assert hasattr(Behavior, name), f"{group}: {name} has no default"
    # the evaluation extras' defaults say "as trained"
    assert Behavior.eval_start(behavior) is None and Behavior.eval_stage(behavior) is None
    assert Behavior.run_metrics(behavior) is None
    assert Evaluator().episode_record() is None and Evaluator.mergeable is False


def test_the_class_source_lists_the_core_first():
    """In ``Behavior`` and the class ``devlearn new`` writes, every core member comes before
    every optional one."""
    source = inspect.getsource(Behavior)
    template = (
        Path(devlearn.__file__).parent / "templates" / "plugin" / "behavior.py.tmpl"
    ).read_text()
    template = template[template.index("(devlearn.Behavior):") :]
    optional = {n for names in BEHAVIOR_OPTIONAL.values() for n in names}
    for text in (source, template):
        order = [
            m.group(1) or m.group(2)
            for m in re.finditer(r"^    (?:def (\w+)|(\w+)(?:: [^=\n]+)? =?)", text, re.MULTILINE)
        ]
        written = [n for n in order if n in optional or n in BEHAVIOR_CORE]
        last_core = max(i for i, n in enumerate(written) if n in BEHAVIOR_CORE)
        first_optional = min(i for i, n in enumerate(written) if n in optional)
        assert last_core < first_optional, written
