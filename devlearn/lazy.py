"""Lazy exports: a package names its public objects and imports each on first use."""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any


def lazy_getattr(package: str, table: dict[str, str], namespace: dict[str, Any]) -> Callable:
    """A module ``__getattr__`` for ``package``: ``name`` is imported from ``table[name]`` on
    first use and stored in ``namespace`` (the package's globals), so later look-ups skip it.

    Keeps heavy dependencies (torch, MuJoCo) out of commands that never touch them.
    """

    def __getattr__(name: str) -> Any:
        module = table.get(name)
        if module is None:
            raise AttributeError(f"module '{package}' has no attribute '{name}'")
        value = getattr(importlib.import_module(module), name)
        namespace[name] = value
        return value

    return __getattr__
