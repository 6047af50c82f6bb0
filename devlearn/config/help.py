"""Every config key of a run with its type, default and docstring (``devlearn config``)."""

from __future__ import annotations

import ast
import dataclasses
import inspect
import textwrap
from typing import TYPE_CHECKING, Any

from devlearn.config.values import field_types, is_term_table, type_name

if TYPE_CHECKING:
    from devlearn.config.run_config import RunConfig


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
        docs, hints = field_docs(type(obj)), field_types(obj)
        for f in dataclasses.fields(obj):
            value = getattr(obj, f.name)
            before = getattr(base, f.name, None) if base is not None else None
            if dataclasses.is_dataclass(value):
                walk(value, before, f"{prefix}{f.name}.")
                continue
            if is_term_table(value):  # a behaviour's reward terms: every entry's keys
                rows.extend(term_rows(value, before, f"{prefix}{f.name}.", base is not None))
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


def term_rows(
    table: dict[str, Any], before: dict[str, Any] | None, prefix: str, marked: bool
) -> list[dict[str, Any]]:
    """The keys of a table of reward terms (``behavior.rewards``): each term's ``cls``,
    ``weight`` and every ``params`` entry, documented by the term class's first line."""
    rows = []
    for name, entry in table.items():
        try:
            summary = (entry.term_class().__doc__ or "").strip().splitlines()[0]
        except (AttributeError, ValueError, IndexError):
            summary = ""
        old = (before or {}).get(name)
        values = {"cls": entry.cls, "weight": entry.weight}
        values.update({f"params.{k}": v for k, v in entry.params.items()})
        for key, value in values.items():
            doc = {
                "cls": f"class of reward term '{name}': {summary}",
                "weight": f"weight of reward term '{name}' (0: pays nothing)",
            }.get(key, f"parameter of reward term '{name}'")
            row = {
                "key": f"{prefix}{name}.{key}",
                "type": type_name(type(value)),
                "default": _json_ready(value),
                "doc": doc,
            }
            if marked:
                was = None
                if old is not None:
                    was = (
                        old.params.get(key[7:]) if key.startswith("params.") else getattr(old, key)
                    )
                row["set_by"] = "core" if was == value else "behavior"
            rows.append(row)
    return rows
