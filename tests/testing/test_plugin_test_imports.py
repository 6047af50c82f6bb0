"""Plugin and example tests use only devlearn's public face (issue #42): ``devlearn``,
``devlearn.api`` and ``devlearn.testing``, the contract ``lint-imports`` checks for their
sources. A test folder is not a package, so import-linter cannot see it: its imports are read
here from the source (``ast``; imports inside functions count)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PUBLIC = ("devlearn.api", "devlearn.testing")
"""The packages (and their modules) a plugin's tests may import from devlearn, besides the
``devlearn`` package itself (its names, not its submodules)."""
ALSO = {"examples/sb3": ("devlearn.gym",)}
"""More public face for one example: the SB3 example is another learner written against the
Gymnasium interface (``devlearn.gym``), which its own source imports too."""
TEST_FOLDERS = sorted([*ROOT.glob("plugins/*/tests"), *ROOT.glob("examples/*/tests")])


def outside_public_face(source: str, allowed: tuple[str, ...] = PUBLIC) -> list[str]:
    """``line: module`` for every import of a devlearn module outside ``allowed``."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names = [node.module]
        else:
            continue
        for name in names:
            if name.split(".")[0] != "devlearn" or name == "devlearn":
                continue  # the plugin's own package, third-party modules, the public names
            if not any(name == face or name.startswith(face + ".") for face in allowed):
                found.append((node.lineno, name))
    return [f"{line}: {name}" for line, name in sorted(found)]


def test_the_check_finds_an_internal_import():
    source = (
        "import numpy\nfrom devlearn import Behavior\n"
        "from devlearn.testing.envs import step_batch\n"
        "def f():\n    from devlearn.training.checkpoint import load_checkpoint\n"
        "import devlearn.env.workers\nfrom devlearn_self_touch import SelfTouch\n"
    )
    assert outside_public_face(source) == [
        "5: devlearn.training.checkpoint",
        "6: devlearn.env.workers",
    ]


@pytest.mark.parametrize("folder", TEST_FOLDERS, ids=lambda f: str(f.relative_to(ROOT)))
def test_plugin_tests_import_only_the_public_face(folder):
    assert TEST_FOLDERS, "no plugin test folders found"
    allowed = PUBLIC + ALSO.get(str(folder.parent.relative_to(ROOT)), ())
    bad = {
        str(path.relative_to(ROOT)): found
        for path in sorted(folder.rglob("*.py"))
        if (found := outside_public_face(path.read_text(), allowed))
    }
    assert bad == {}, f"import only devlearn, {', '.join(allowed)} (see devlearn.testing.runs)"
