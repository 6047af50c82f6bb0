"""The walk of one setting (issue #42's measure for a reader of the code): the files a value given
by ``--set KEY=VALUE`` passes through from the command line to its use, and how many times it
enters each.

Runs ``devlearn run BEHAVIOR --set KEY=VALUE OPTIONS`` in this process under a profiler and
records every call, in devlearn's or a plugin's code, that is handed the value: an argument
(``self`` included) equal to it, a string holding it, or a dict, list, dataclass or object
holding it at most ``DEPTH`` levels down (a behaviour config's ``rewards[TERM].weight``, a
term's ``.weight``, ``["KEY=VALUE"]``). A whole run config
(``cfg.behavior.rewards[TERM].weight``), or a behaviour holding its config, is passed around
but not read there and does not count. Consecutive such calls in one file are one entry into
it. It stops at the first call of ``STOP``, where the value is used (``term_values``
multiplies each reward term by its weight), counted as the last entry.

    python scripts/walk_setting.py self_touch behavior.rewards.balance.weight 0.7311

Choose a value that appears nowhere else (a weight of 1.0 would be found everywhere).
"""

from __future__ import annotations

import dataclasses
import os
import sys
import tempfile
from collections import Counter
from pathlib import Path
from typing import Any

STOP = "term_values"
DEPTH = 3
"""How deep in an argument the value may lie: a behaviour config's ``rewards[TERM].weight``."""


def holds(obj: Any, value: float, text: str, depth: int = DEPTH, seen: set | None = None) -> bool:
    """Whether ``obj`` is, names or holds ``value`` within ``depth`` levels."""
    if isinstance(obj, bool) or obj is None:
        return False
    if isinstance(obj, (int, float)):
        return obj == value
    if isinstance(obj, str):
        return text in obj
    if depth == 0 or type(obj).__module__ in ("numpy", "torch") or callable(obj):
        return False
    seen = seen if seen is not None else set()
    if id(obj) in seen:
        return False
    seen.add(id(obj))
    if isinstance(obj, dict):
        items = list(obj.values())
    elif isinstance(obj, (list, tuple)):
        items = list(obj)
    elif dataclasses.is_dataclass(obj):
        items = [getattr(obj, f.name, None) for f in dataclasses.fields(obj)]
    elif type(obj).__module__.startswith("devlearn") and isinstance(
        getattr(obj, "__dict__", None), dict
    ):
        items = list(vars(obj).values())  # devlearn's and plugins' objects, not MuJoCo's
    else:
        return False
    return any(holds(item, value, text, depth - 1, seen) for item in items[:200])


def main(argv: list[str]) -> int:
    behavior, key, shown = argv[:3]
    value, root = float(shown), Path(__file__).resolve().parents[1]
    walk: list[tuple[str, str]] = []

    def profile(frame: Any, event: str, arg: Any) -> None:
        if event != "call":
            return
        path = frame.f_code.co_filename
        if "devlearn" not in path or "site-packages" in path:
            return
        code = frame.f_code
        names = code.co_varnames[: code.co_argcount + code.co_kwonlyargcount]
        where = str(Path(path).resolve().relative_to(root))
        if code.co_name == STOP or any(holds(frame.f_locals.get(n), value, shown) for n in names):
            walk.append((where, code.co_name))
        if code.co_name == STOP:
            sys.setprofile(None)
            report(walk)
            os._exit(0)

    from devlearn.cli import main as devlearn

    out = Path(tempfile.mkdtemp(prefix="walk-")) / "run"
    args = ["run", behavior, "--set", f"{key}={shown}", "--steps", "320", "--envs", "1"]
    args += ["--workers", "0", "--out", str(out), *argv[3:]]
    sys.setprofile(profile)
    devlearn(args)
    sys.setprofile(None)
    print(f"{STOP} was never called", file=sys.stderr)
    return 1


def report(walk: list[tuple[str, str]]) -> None:
    """The entries in order, then the files with how many times the value entered each."""
    entries: list[tuple[str, list[str]]] = []
    for where, function in walk:
        if entries and entries[-1][0] == where:
            entries[-1][1].append(function)
        else:
            entries.append((where, [function]))
    for i, (where, functions) in enumerate(entries, 1):
        print(f"{i:2d}. {where}: {' > '.join(functions)}")
    counts = Counter(where for where, _ in entries)
    print(f"\n{len(counts)} files, {len(entries)} entries; entries per file:")
    for where, n in counts.most_common():
        print(f"  {n}  {where}")


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
