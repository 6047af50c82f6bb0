"""``devlearn.testing`` speaks in behaviour-level verbs (issue #59): what it exports is the
conformance kit, its fixtures and the verbs (play steps, term values, a config round trip, a
tiny run), never the core's internals, and plugin tests take their names from it alone."""

from __future__ import annotations

import ast
import importlib
import importlib.util
import pkgutil
from pathlib import Path

import devlearn.testing

ROOT = Path(__file__).resolve().parents[2]
INTERNALS = {
    "BehaviorEnv",
    "DevVecEnv",
    "make_envs",
    "step_batch",
    "share_batched_terms",
    "term_values",
    "from_dict",
    "to_dict",
    "load_run_config",
    "RunConfig",
    "EnvSettings",
    "WorkerPool",
}
"""The core's classes and functions plugin tests used to take from ``devlearn.testing``."""


def test_the_kit_exports_no_core_internals():
    exported = set(devlearn.testing.__all__)
    assert not exported & INTERNALS
    for module in pkgutil.iter_modules(devlearn.testing.__path__):
        names = set(
            getattr(importlib.import_module(f"devlearn.testing.{module.name}"), "__all__", ())
        )
        assert not names & INTERNALS, (module.name, sorted(names & INTERNALS))
    assert importlib.util.find_spec("devlearn.testing.envs") is None  # the re-export module


def test_plugin_tests_take_their_names_from_the_kit():
    folders = [*ROOT.glob("plugins/*/tests"), *ROOT.glob("examples/*/tests")]
    kit = set(devlearn.testing.__all__)
    taken = {}
    for path in sorted(p for folder in folders for p in folder.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith(
                "devlearn.testing"
            ):
                for alias in node.names:
                    taken[f"{path.relative_to(ROOT)}: {node.module}.{alias.name}"] = (
                        node.module == "devlearn.testing" and alias.name in kit
                    )
    assert taken and [name for name, ok in taken.items() if not ok] == []
