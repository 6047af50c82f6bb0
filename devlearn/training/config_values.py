"""Config values: a command-line string or JSON value converted to a config field's declared
type, with errors that say what the field expects."""

from __future__ import annotations

import dataclasses
import json
import types
import typing
from typing import Any

from devlearn.errors import UsageError


def convert(value: Any, kind: Any, key: str) -> Any:
    """Convert a string (from the command line) or JSON value to a field's declared type."""
    origin, args = typing.get_origin(kind), typing.get_args(kind)
    if origin in (typing.Union, types.UnionType):
        if value is None or (isinstance(value, str) and value.lower() in ("none", "null")):
            if type(None) in args:
                return None
        for arg in (a for a in args if a is not type(None)):
            try:
                return convert(value, arg, key)
            except (UsageError, ValueError, TypeError):
                pass
        raise UsageError(f"bad value {value!r} for {key}: expected {_expected(kind)}")
    try:
        if kind is bool:
            if isinstance(value, str):
                text = value.strip().lower()
                if text not in ("true", "false", "1", "0", "yes", "no"):
                    raise ValueError("expected true or false")
                return text in ("true", "1", "yes")
            return bool(value)
        if kind is int:
            number = float(value)
            if not number.is_integer():
                raise ValueError("expected an integer")
            return int(number)
        if kind is float:
            return float(value)
        if kind is str:
            return str(value)
        if origin in (tuple, list) or kind in (tuple, list):
            items = value
            if isinstance(value, str):
                text = value.strip()
                items = (
                    json.loads(text)
                    if text.startswith("[")
                    else [s for s in text.split(",") if s.strip()]
                )
            item_kind = args[0] if args else Any
            items = [convert(v, item_kind, key) for v in items]
            return tuple(items) if (origin or kind) is tuple else list(items)
        if isinstance(value, str) and (origin is dict or kind is dict):
            return json.loads(value)
    except (ValueError, TypeError):
        raise UsageError(f"bad value {value!r} for {key}: expected {_expected(kind)}") from None
    return value


def _expected(kind: Any) -> str:
    """``int (a whole number, e.g. 16 or 2e6)``: a field's type, for error messages."""
    from devlearn.training.config_help import type_name

    origin = typing.get_origin(kind) or kind
    examples = {
        int: "a whole number, e.g. 16 or 2e6",
        float: "a number, e.g. 3e-4",
        bool: "true or false",
        tuple: "comma-separated values or a JSON list",
        list: "comma-separated values or a JSON list",
        dict: "a JSON object",
    }
    if origin in (typing.Union, types.UnionType):
        return " or ".join(_expected(a) for a in typing.get_args(kind))
    if kind is type(None):
        return "none"
    example = examples.get(origin)
    return f"{type_name(kind)} ({example})" if example else type_name(kind)


def field_types(obj: Any) -> dict[str, Any]:
    """A dataclass instance's field types by name (its annotations resolved; where they do not
    resolve, the runtime values' types)."""
    try:
        return typing.get_type_hints(type(obj))
    except Exception:  # unresolvable annotations: fall back to the runtime value's type
        return {f.name: type(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
