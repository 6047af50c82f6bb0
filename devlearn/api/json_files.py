"""The one guarded reader of the JSON files a command is given (configs, evaluations, metrics,
detector files, sweep records): a regular file only (``/dev/zero`` was read until memory ran
out, a pipe waits for a writer), at most a size cap, nested at most :data:`MAX_DEPTH` levels
(deeper JSON raised RecursionError in the parser, or later in any code that walks it). Every
failure is one :class:`~devlearn.api.errors.UsageError` line naming the file and the cause."""

from __future__ import annotations

import json
import os
import stat
from collections.abc import Callable
from pathlib import Path
from typing import Any

from devlearn.api.errors import UsageError

MAX_BYTES = 64 << 20
"""Largest JSON file read (64 MiB): a run's config, an eval.json or a detector file is a few
kilobytes; anything this large is not one of them."""
MAX_LINES_BYTES = 1 << 30
"""Largest JSON-lines file read (1 GiB): a run's ``metrics.jsonl`` grows by a row of about
2 kB per iteration, some 100 MB for a run of 100M steps."""
MAX_DEPTH = 100
"""Deepest nesting of arrays and objects read (a config is 4 levels deep)."""


class NestedTooDeeply(UsageError):
    """JSON nested deeper than :data:`MAX_DEPTH` levels (or than Python's parser recurses)."""


def read_text(path: str | Path, max_bytes: int = MAX_BYTES) -> str:
    """The text of the regular file ``path``, at most ``max_bytes`` bytes, as UTF-8.

    Raises:
        UsageError: Missing or unreadable, not a regular file, larger than ``max_bytes`` or
            not UTF-8 text.
    """
    path = Path(path)
    try:
        # opened without blocking: a FIFO would wait for a writer before fstat could refuse it
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        raise UsageError(f"cannot read {path}: {exc.strerror or exc}") from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise UsageError(f"cannot read {path}: {_kind(info.st_mode)}, not a file")
        if info.st_size > max_bytes:
            raise UsageError(
                f"cannot read {path}: {info.st_size:,} bytes, more than the "
                f"{max_bytes:,} a file of this kind may hold"
            )
        with os.fdopen(os.dup(fd), "rb") as f:
            data = f.read(max_bytes + 1)  # a file that grew since fstat is cut here
    except OSError as exc:
        raise UsageError(f"cannot read {path}: {exc.strerror or exc}") from None
    finally:
        os.close(fd)
    if len(data) > max_bytes:
        raise UsageError(f"cannot read {path}: more than {max_bytes:,} bytes")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise UsageError(f"cannot read {path}: it is not text (not UTF-8)") from None


def _kind(mode: int) -> str:
    kinds = [
        (stat.S_ISDIR, "a folder"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISFIFO, "a pipe"),
        (stat.S_ISSOCK, "a socket"),
    ]
    return next((name for test, name in kinds if test(mode)), "not a regular file")


def parse_json(text: str, source: str) -> Any:
    """The JSON value ``text`` holds, nested at most :data:`MAX_DEPTH` levels.

    Args:
        text: JSON text.
        source: What it is, for the error (``cannot read SOURCE: ...``): a path, an option.
    Raises:
        NestedTooDeeply: Nested too deeply (a :class:`UsageError`).
        UsageError: Not JSON.
    """
    try:
        value = json.loads(text)
    except RecursionError:
        raise NestedTooDeeply(f"cannot read {source}: its JSON is nested too deeply") from None
    except ValueError as exc:
        raise UsageError(f"cannot read {source}: not JSON ({exc})") from None
    if _depth(value) > MAX_DEPTH:
        raise NestedTooDeeply(
            f"cannot read {source}: its JSON is nested too deeply (more than {MAX_DEPTH} levels)"
        )
    return value


def _depth(value: Any) -> int:
    """Levels of arrays and objects in a parsed JSON value (0 for a number or a string),
    walked without recursion; stops counting past :data:`MAX_DEPTH`."""
    if not isinstance(value, dict | list):
        return 0
    deepest = 0
    stack: list[tuple[dict | list, int]] = [(value, 1)]
    while stack and deepest <= MAX_DEPTH:
        item, level = stack.pop()
        deepest = max(deepest, level)
        children = item.values() if isinstance(item, dict) else item
        stack.extend((child, level + 1) for child in children if isinstance(child, dict | list))
    return deepest


def read_json(path: str | Path, max_bytes: int = MAX_BYTES) -> Any:
    """The JSON value in the file ``path``: :func:`read_text` then :func:`parse_json`.

    Raises:
        UsageError: One line naming ``path`` and the cause.
    """
    return parse_json(read_text(path, max_bytes), str(path))


def read_json_object(path: str | Path, what: str, max_bytes: int = MAX_BYTES) -> dict[str, Any]:
    """The JSON object in the file ``path`` (:func:`read_json`), which is ``what`` (``a run
    config``, ``an evaluation``): anything but an object is refused.

    Raises:
        UsageError: Unreadable (:func:`read_json`), or not a JSON object.
    """
    data = read_json(path, max_bytes)
    if not isinstance(data, dict):
        raise UsageError(
            f"{path} is not {what}: it holds a JSON {type(data).__name__}, not an object"
        )
    return data


def read_json_lines(
    path: str | Path,
    keep: Callable[[dict[str, Any]], bool] | None = None,
    max_bytes: int = MAX_LINES_BYTES,
) -> tuple[list[dict[str, Any]], list[int]]:
    """The JSON objects of a JSON-lines file (``metrics.jsonl``), one a line, with the numbers
    (from 1) of the lines that are none: garbled, not an object, too deep, or an object
    ``keep`` refuses. Blank lines are neither, and neither is a last line without its newline
    that is no object (being written, or cut short by a kill): it is left out.

    Raises:
        UsageError: The file cannot be read at all (:func:`read_text`, but undecodable bytes
            spoil only their lines).
    """
    path = Path(path)
    garbled = False  # some bytes are not UTF-8: the lines that hold them are no rows
    try:
        text = read_text(path, max_bytes)
    except UsageError as err:
        if "not UTF-8" not in str(err):
            raise
        text = Path(path).read_bytes()[: max_bytes + 1].decode("utf-8", errors="replace")
        garbled = True
    rows, bad = [], []
    lines = text.splitlines()
    for number, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            spoilt = garbled and "\ufffd" in line
            row = None if spoilt else parse_json(line, f"{path} line {number}")
        except UsageError:
            row = None
        if isinstance(row, dict) and (keep is None or keep(row)):
            rows.append(row)
        elif isinstance(row, dict) or number < len(lines) or text.endswith("\n"):
            bad.append(number)
    return rows, bad
