"""Config values: a command-line string or JSON value converted to a config field's declared
type, with errors that say what the field expects, and set by dotted key (``--set a.b=value``)
on a :class:`~devlearn.config.run_config.RunConfig`; an unknown key is answered with the closest
valid one."""

from __future__ import annotations

import dataclasses
import difflib
import types
import typing
from typing import Any

from devlearn.api.errors import UsageError
from devlearn.api.json_files import NestedTooDeeply, parse_json


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
        raise UsageError(f"bad value {_shown(value)} for {key}: expected {_expected(kind)}")
    try:
        if kind is bool:
            if isinstance(value, str):
                text = value.strip().lower()
                if text not in ("true", "false", "1", "0", "yes", "no"):
                    raise ValueError("expected true or false")
                return text in ("true", "1", "yes")
            if isinstance(value, bool) or (isinstance(value, int) and value in (0, 1)):
                return bool(value)  # JSON: true, false, 1, 0; not 7, [] or null
            raise ValueError("expected true or false")
        if kind in (int, float) and isinstance(value, bool):
            raise ValueError("expected a number, not true or false")
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
                    _json(text, key)
                    if text.startswith("[")
                    else [s for s in text.split(",") if s.strip()]
                )
            item_kind = args[0] if args else Any
            items = [convert(v, item_kind, key) for v in items]
            return tuple(items) if (origin or kind) is tuple else list(items)
        if origin is dict or kind is dict:
            table = _json(value, key) if isinstance(value, str) else value
            if not isinstance(table, dict):
                raise ValueError("expected a table")
            entry = args[1] if len(args) == 2 else None
            if isinstance(entry, type) and dataclasses.is_dataclass(entry):
                # a saved table of dataclasses (a behaviour's ``rewards``): rebuild each entry
                return {k: v if isinstance(v, entry) else entry(**v) for k, v in table.items()}
            return table
    except (ValueError, TypeError):
        raise UsageError(
            f"bad value {_shown(value)} for {key}: expected {_expected(kind)}"
        ) from None
    return value


def _shown(value: Any) -> str:
    """``repr(value)``, cut to 80 characters (a pasted file is no error message)."""
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _json(text: str, key: str) -> Any:
    """The JSON value of a ``--set`` list or table (:func:`~devlearn.api.json_files.parse_json`).

    Raises:
        NestedTooDeeply: Nested too deeply (a one-line UsageError saying so).
        ValueError: Not JSON (answered with what the field expects).
    """
    try:
        return parse_json(text, f"--set {key}")
    except NestedTooDeeply:
        raise
    except UsageError as err:
        raise ValueError(str(err)) from None


def _expected(kind: Any) -> str:
    """``int (a whole number, e.g. 16 or 2e6)``: a field's type, for error messages."""
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


def type_name(kind: Any) -> str:
    """A short, readable name of a field's type: ``int``, ``float | None``, ``tuple[int, ...]``."""
    if isinstance(kind, type) and not typing.get_args(kind):
        return kind.__name__
    text = str(kind).replace("typing.", "").replace("NoneType", "None")
    return text.replace("Optional[", "None | ").rstrip("]") if "Optional[" in text else text


def field_types(obj: Any) -> dict[str, Any]:
    """A dataclass instance's field types by name (its annotations resolved; where they do not
    resolve, the runtime values' types)."""
    try:
        return typing.get_type_hints(type(obj))
    except Exception:  # unresolvable annotations: fall back to the runtime value's type
        return {f.name: type(getattr(obj, f.name)) for f in dataclasses.fields(obj)}


RECORDED_ONLY = {"preset": "--preset NAME", "start_from": "--from CHECKPOINT"}
"""RunConfig fields set by a command-line flag, not by ``--set`` (field -> the flag)."""


def is_term_table(value: Any) -> bool:
    """Whether ``value`` is a table of dataclasses (a behaviour's ``rewards``: name ->
    RewardTermCfg), whose entries' fields are keys too (``behavior.rewards.balance.weight``)."""
    return (
        isinstance(value, dict)
        and bool(value)
        and all(dataclasses.is_dataclass(v) for v in value.values())
    )


def _leaf_keys(obj: Any, prefix: str = "", in_entry: bool = False) -> list[str]:
    keys = []
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        if dataclasses.is_dataclass(value):
            keys += _leaf_keys(value, f"{prefix}{f.name}.")
        elif is_term_table(value):
            for name, entry in value.items():
                keys += _leaf_keys(entry, f"{prefix}{f.name}.{name}.", in_entry=True)
        elif in_entry and isinstance(value, dict):  # a term's params: one key each
            keys += [f"{prefix}{f.name}.{name}" for name in value]
        else:
            keys.append(prefix + f.name)
    return keys


def valid_keys(cfg: Any) -> list[str]:
    """Return every overridable dotted key (``ppo.learning_rate``, ``behavior.stage_steps``,
    ``behavior.rewards.balance.weight``, ``behavior.rewards.balance.params.reward``...)."""
    return _leaf_keys(cfg)


def in_table(cfg: Any, key: str) -> bool:
    """Whether dotted ``key`` names an entry of a free-form table field (``learned.rnd.weight``),
    which :func:`valid_keys` does not list."""
    head, _, rest = key.partition(".")
    return bool(rest) and isinstance(getattr(cfg, head, None), dict)


def _value_kind(current: Any) -> Any:
    """The type a new value of a table entry is converted to: that of the value it replaces."""
    if isinstance(current, tuple) and current:
        return tuple[type(current[0]), ...]  # type: ignore[misc]
    if isinstance(current, list) and current:
        return list[type(current[0])]  # type: ignore[misc]
    return Any if current is None else type(current)


def _unknown_in_table(key: str, where: str, name: str, table: dict) -> UsageError:
    """``unknown key 'balanse' in 'behavior.rewards'; did you mean 'balance'? valid: ...``."""
    match = difflib.get_close_matches(name, list(table), n=1, cutoff=0.6)
    hint = f"; did you mean '{match[0]}'?" if match else ""
    return UsageError(
        f"unknown config key '{key}': no '{name}' in '{where}'{hint} "
        f"(valid: {', '.join(table) or 'none'})"
    )


def set_value(cfg: Any, key: str, value: Any) -> None:
    """Set dotted ``key`` to ``value`` (converted to the field's type); UsageError if unknown.

    Keys go through dataclass fields and through tables of them (a behaviour's ``rewards``:
    ``behavior.rewards.balance.weight``, ``behavior.rewards.balance.params.reward``); an
    unknown table entry is answered with the valid ones.
    """
    head, _, rest = key.partition(".")
    if in_table(cfg, key):
        # A table of free-form options (``learned.rnd.weight``): kept as given here, then
        # converted and checked against the term's own config class when the run builds it.
        *path, leaf = rest.split(".")
        table = getattr(cfg, head)
        for part in path:
            table = table.setdefault(part, {})
            if not isinstance(table, dict):
                raise UsageError(f"config key '{key}' goes inside a value that is not a table")
        table[leaf] = value
        return
    if key in RECORDED_ONLY:
        raise UsageError(f"'{key}' is set with {RECORDED_ONLY[key]}, not with --set")
    *path, leaf = key.split(".")
    obj: Any = cfg
    for depth, part in enumerate(path):
        if isinstance(obj, dict):  # an entry of a table (``rewards.balance``, ``params``)
            if part not in obj:
                raise _unknown_in_table(key, ".".join(path[:depth]), part, obj)
            obj = obj[part]
        else:
            obj = getattr(obj, part, None) if dataclasses.is_dataclass(obj) else None
    if isinstance(obj, dict) and path:
        if leaf not in obj:
            raise _unknown_in_table(key, ".".join(path), leaf, obj)
        if dataclasses.is_dataclass(obj[leaf]):
            fields = ", ".join(f.name for f in dataclasses.fields(obj[leaf]))
            raise UsageError(f"config key '{key}' is a table; set one of its keys ({fields})")
        obj[leaf] = convert(value, _value_kind(obj[leaf]), key)
        return
    names = {f.name for f in dataclasses.fields(obj)} if dataclasses.is_dataclass(obj) else set()
    if leaf not in names or dataclasses.is_dataclass(getattr(obj, leaf)):
        raise UsageError(unknown_key_message(key, cfg))
    if is_term_table(getattr(obj, leaf)):
        entries = ", ".join(getattr(obj, leaf))
        raise UsageError(f"config key '{key}' is a table; set a key of one of {entries}")
    setattr(obj, leaf, convert(value, field_types(obj).get(leaf, Any), key))


def apply_overrides(cfg: Any, overrides: list[str] | dict[str, Any]) -> Any:
    """Apply ``["ppo.learning_rate=3e-4", ...]`` (or a dict of dotted keys) to ``cfg`` in place.

    Raises:
        UsageError: An item without ``=``, an unknown key (the closest valid one is
            suggested) or a value that does not convert to the field's type.
    """
    if isinstance(overrides, dict):
        items = list(overrides.items())
    else:
        items = []
        for text in overrides:
            key, sep, value = text.partition("=")
            if not sep or not key.strip():
                raise UsageError(f"override '{text}' must look like key=value (e.g. seed=3)")
            items.append((key.strip(), value.strip()))
    for key, value in items:
        set_value(cfg, key, value)
    return cfg


def override_keys(overrides: list[str] | dict[str, Any] | None) -> set[str]:
    """The dotted keys that ``overrides`` (as :func:`apply_overrides` takes them) sets."""
    if isinstance(overrides, dict):
        return {str(key).strip() for key in overrides}
    return {text.partition("=")[0].strip() for text in overrides or []}


def suggest_key(key: str, keys: list[str]) -> str | None:
    """The valid key closest to a mistyped ``key`` (by its last part, then as a whole)."""
    leaf = key.rsplit(".", 1)[-1]
    leaves = {k.rsplit(".", 1)[-1]: k for k in keys}
    started = [k for name, k in leaves.items() if len(leaf) >= 3 and name.startswith(leaf)]
    if len(started) == 1:  # an abbreviation: ppo.clip -> ppo.clip_param
        return started[0]
    initials = [k for name, k in leaves.items() if "_" in name and leaf == _initials(name)]
    if len(initials) == 1:  # ppo.lr -> ppo.learning_rate
        return initials[0]
    match = difflib.get_close_matches(leaf, list(leaves), n=1, cutoff=0.6)
    if match:
        return leaves[match[0]]
    match = difflib.get_close_matches(key, keys, n=1, cutoff=0.75)
    return match[0] if match else None


def _initials(name: str) -> str:
    return "".join(word[:1] for word in name.split("_"))


def unknown_key_message(key: str, cfg: Any) -> str:
    """``unknown config key 'ppo.lr'; did you mean 'ppo.learning_rate'? ...`` (one line).

    A key under a section (``ppo.``, ``behavior.``) is matched against that section's keys;
    a section given alone is told to name one of its keys.
    """
    keys = valid_keys(cfg)
    name = cfg.behavior_name or "BEHAVIOR"
    where = f"(`devlearn config {name}` lists all {len(keys)})"
    sections = {k.split(".", 1)[0] for k in keys if "." in k}
    if key in sections:
        first = next(k for k in keys if k.startswith(key + "."))
        return f"config key '{key}' is a section; set one of its keys, e.g. {first} {where}"
    section = key.split(".", 1)[0] if "." in key else ""
    candidates = [k for k in keys if k.startswith(section + ".")] if section in sections else keys
    guess = suggest_key(key, candidates)
    if guess is None and candidates is not keys and len(candidates) <= 12:
        return f"unknown config key '{key}'; {section} keys: {', '.join(candidates)}"
    hint = f"; did you mean '{guess}'?" if guess else ""
    return f"unknown config key '{key}'{hint} {where}"
