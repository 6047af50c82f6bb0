"""Every test module's file name is unique across the suite's folders: without packages
(no ``__init__.py``), pytest imports test modules by their base name, and a second
``test_analysis.py`` in another plugin stops the whole suite at collection (it did, when both
plugins gained their analyses)."""

from __future__ import annotations

import tomllib
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_no_two_test_modules_share_a_name():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    folders = config["tool"]["pytest"]["ini_options"]["testpaths"]
    by_name: dict[str, list[str]] = defaultdict(list)
    for folder in folders:
        for path in (ROOT / folder).rglob("*.py"):
            if path.name.startswith("test_"):
                by_name[path.name].append(str(path.relative_to(ROOT)))
    assert by_name, "no test modules found: the testpaths moved?"
    shared = {name: paths for name, paths in by_name.items() if len(paths) > 1}
    assert not shared, f"test modules sharing a name (rename one): {shared}"
