"""The value checks of devlearn's conformance kit: the error, and whether a value is a finite
number, pickles (to reach worker processes) and serialises to JSON (eval.json)."""

from __future__ import annotations

import json
import math
import numbers
import pickle
from typing import Any

import numpy as np


class ConformanceError(AssertionError):
    """A behaviour breaks the devlearn contract; the message says which part."""


def require(condition: bool, message: str) -> None:
    """Raise :class:`ConformanceError` with ``message`` unless ``condition``."""
    if not condition:
        raise ConformanceError(message)


def pickle_problem(obj: Any, label: str, depth: int = 0) -> str | None:
    """Return why ``obj`` cannot be pickled, naming the innermost attribute at fault, or None.

    Args:
        obj: The object to pickle.
        label: How to name it in the message (``behavior 'x'``, ``self.cache``...).
        depth: Recursion depth (attributes of attributes, up to 4 levels).
    """
    try:
        pickle.dumps(obj)
        return None
    except Exception as exc:  # noqa: BLE001 - any pickling failure is reported by name
        error = f"{type(exc).__name__}: {exc}"
    children: list[tuple[str, Any]] = []
    if isinstance(obj, dict):
        children = [(f"{label}[{k!r}]", v) for k, v in obj.items()]
    elif isinstance(obj, (list, tuple, set)):
        children = [(f"{label}[{i}]", v) for i, v in enumerate(obj)]
    elif hasattr(obj, "__dict__") and not callable(obj):
        children = [(f"{label}.{k}", v) for k, v in vars(obj).items()]
    if depth < 4:
        for child_label, child in children:
            found = pickle_problem(child, child_label, depth + 1)
            if found:
                return found
    hint = ""
    if "attribute lookup" in error or "<locals>" in error:
        hint = " (define the class at module level, where pickle can import it)"
    return f"{label} (a {type(obj).__module__}.{type(obj).__qualname__}): {error}{hint}"


def check_picklable(obj: Any, what: str, label: str = "self") -> None:
    """Raise ConformanceError naming the attribute that stops ``obj`` from pickling."""
    problem = pickle_problem(obj, label)
    require(
        problem is None, f"{what} cannot be pickled (it is sent to worker processes): {problem}"
    )


def check_number(value: Any, what: str, where: str = "") -> float:
    """Return ``value`` as a float if it is a finite real number (not a bool); else raise.

    Args:
        value: What a term or an evaluator returned.
        what: Who returned it (``reward term 'x'``), for the message.
        where: When (``on a step with a hand placed on the body``), for the message.
    """
    is_number = isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))
    finite = is_number and math.isfinite(float(value))
    if not finite:
        shown = " ".join(repr(value).split())[:60]
        when = f" {where}" if where else ""
        raise ConformanceError(
            f"{what} returned {shown} (a {type(value).__name__}){when}; "
            "it must return a finite Python float"
        )
    return float(value)


def json_problem(value: Any, label: str) -> str | None:
    """Return the first part of ``value`` that ``json.dumps`` rejects (with its path), or None."""
    try:
        json.dumps(value, allow_nan=True)
        return None
    except (TypeError, ValueError):
        pass
    if isinstance(value, dict):
        for key, item in value.items():
            if not isinstance(key, (str, int, float, bool)) and key is not None:
                return f"{label} has a key {key!r} of type {type(key).__name__}"
            found = json_problem(item, f"{label}[{key!r}]")
            if found:
                return found
    elif isinstance(value, (list, tuple)):
        for i, item in enumerate(value):
            found = json_problem(item, f"{label}[{i}]")
            if found:
                return found
    return f"{label} is a {type(value).__module__}.{type(value).__qualname__}"
