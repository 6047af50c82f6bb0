"""Every hook is documented: a full docstring, and a section in docs/writing-a-plugin.md."""

from __future__ import annotations

import inspect
from pathlib import Path

from devlearn.api import hookspecs

DOC = Path(__file__).resolve().parents[2] / "docs" / "writing-a-plugin.md"


def _hooks():
    return [
        (name, fn)
        for name, fn in inspect.getmembers(hookspecs, inspect.isfunction)
        if hasattr(fn, "devlearn_spec")
    ]


def test_there_are_hooks():
    assert {name for name, _ in _hooks()} >= {"register_behaviors", "register_learned_rewards"}


def test_every_hook_has_a_docstring_with_args():
    for name, fn in _hooks():
        doc = inspect.getdoc(fn) or ""
        assert len(doc.splitlines()) >= 3, f"hook {name} needs a full docstring"
        for param in inspect.signature(fn).parameters:
            assert param in doc, f"hook {name} does not document its argument '{param}'"


def test_every_hook_is_in_the_plugin_guide():
    text = DOC.read_text()
    for name, _ in _hooks():
        assert f"`{name}" in text, f"hook {name} is missing from {DOC.name}"
