"""Every config key of a run with its type, default and docstring (``devlearn config``)."""

from __future__ import annotations

import ast
import dataclasses
import difflib
import inspect
import textwrap
import typing
from typing import Any

from devlearn.training.config import RunConfig
from devlearn.training.config_values import valid_keys


def type_name(kind: Any) -> str:
    """A short, readable name of a field's type: ``int``, ``float | None``, ``tuple[int, ...]``."""
    if isinstance(kind, type) and not typing.get_args(kind):
        return kind.__name__
    text = str(kind).replace("typing.", "").replace("NoneType", "None")
    return text.replace("Optional[", "None | ").rstrip("]") if "Optional[" in text else text


def field_docs(cls: type) -> dict[str, str]:
    """Return field name -> its docstring (the string literal under the field), '' if none."""
    try:
        source = textwrap.dedent(inspect.getsource(cls))
    except (OSError, TypeError):  # defined interactively: no source to read
        return {}
    tree = ast.parse(source)
    node = next((n for n in tree.body if isinstance(n, ast.ClassDef)), None)
    docs: dict[str, str] = {}
    body = node.body if node else []
    for item, after in zip(body, [*body[1:], None]):
        if isinstance(item, ast.AnnAssign) and isinstance(item.target, ast.Name):
            text = ""
            if isinstance(after, ast.Expr) and isinstance(after.value, ast.Constant):
                text = " ".join(str(after.value.value).split())
            docs[item.target.id] = text
    return docs


def _hints(cls: type) -> dict[str, Any]:
    try:
        return typing.get_type_hints(cls)
    except Exception:  # unresolvable annotations: the declared strings will do
        return {f.name: f.type for f in dataclasses.fields(cls)}


def _json_ready(value: Any) -> Any:
    if isinstance(value, tuple):
        return [_json_ready(v) for v in value]
    if isinstance(value, list):
        return [_json_ready(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _json_ready(v) for k, v in value.items()}
    return value


def describe_keys(cfg: RunConfig, core: RunConfig | None = None) -> list[dict[str, Any]]:
    """Describe every overridable key of ``cfg`` (run, ppo and behaviour fields).

    Args:
        cfg: The config a run would use (defaults, the behaviour's ``train_defaults()``...).
        core: The same config before the behaviour's ``train_defaults()``; keys whose value
            differs are marked ``"set_by": "behavior"``.
    Returns:
        One dict per key: ``key``, ``type``, ``default`` (JSON-ready), ``doc``, ``set_by``
        (``"core"``, ``"behavior"`` or ``"override"`` when ``core`` is given).
    """
    rows: list[dict[str, Any]] = []

    def walk(obj: Any, base: Any, prefix: str) -> None:
        docs, hints = field_docs(type(obj)), _hints(type(obj))
        for f in dataclasses.fields(obj):
            value = getattr(obj, f.name)
            before = getattr(base, f.name, None) if base is not None else None
            if dataclasses.is_dataclass(value):
                walk(value, before, f"{prefix}{f.name}.")
                continue
            row = {
                "key": prefix + f.name,
                "type": type_name(hints.get(f.name, f.type)),
                "default": _json_ready(value),
                "doc": docs.get(f.name, ""),
            }
            if base is not None:
                row["set_by"] = "core" if before == value else "behavior"
            rows.append(row)

    walk(cfg, core, "")
    return rows


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


def unknown_key_message(key: str, cfg: RunConfig) -> str:
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
