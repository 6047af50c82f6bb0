"""The guarded JSON reader every command reads the files it is given with (issue #55, fault 8):
regular files only, a size cap, nesting bounded, each refusal one UsageError line."""

from __future__ import annotations

import os

import pytest

from devlearn.api.errors import UsageError
from devlearn.api.json_files import (
    MAX_DEPTH,
    NestedTooDeeply,
    parse_json,
    read_json,
    read_json_lines,
    read_json_object,
    read_text,
)


def test_only_a_regular_file_of_bounded_size_is_read(tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)  # opened for reading, it would wait for a writer
    for path, reason in [
        ("/dev/zero", "a character device, not a file"),  # read until memory ran out
        (fifo, "a pipe, not a file"),
        (tmp_path, "a folder, not a file"),
        (tmp_path / "missing.json", "No such file or directory"),
    ]:
        with pytest.raises(UsageError, match=f"^cannot read {path}: {reason}$"):
            read_json(path)
    big = tmp_path / "big.json"
    big.write_text("[" + "0," * 600 + "0]")
    with pytest.raises(UsageError, match=r"1,203 bytes, more than the 1,000 a file of this kind"):
        read_text(big, max_bytes=1000)
    assert len(read_json(big, max_bytes=2000)) == 601
    binary = tmp_path / "binary.json"
    binary.write_bytes(b"\x89PNG\r\n")
    with pytest.raises(UsageError, match="it is not text"):
        read_json(binary)


def test_nesting_is_bounded_without_recursion_errors(tmp_path):
    assert parse_json("[" * MAX_DEPTH + "]" * MAX_DEPTH, "x") is not None
    for depth in (MAX_DEPTH + 1, 900, 100_000):  # under, near and past Python's recursion limit
        text = '{"a":' * depth + "1" + "}" * depth
        with pytest.raises(NestedTooDeeply, match="^cannot read x: its JSON is nested too deep"):
            parse_json(text, "x")
    with pytest.raises(UsageError, match=r"^cannot read x: not JSON \(Expecting"):
        parse_json("[1,", "x")
    path = tmp_path / "list.json"
    path.write_text("[1, 2]")
    with pytest.raises(UsageError, match="is not a run config: it holds a JSON list"):
        read_json_object(path, "a run config")


def test_json_lines_keep_the_objects_and_number_the_rest(tmp_path):
    path = tmp_path / "metrics.jsonl"
    lines = ['{"step": 1}', "[1, 2, 3]", "", '{"step": -1}', "[" * 5000 + "]" * 5000, '{"st']
    path.write_text("\n".join(lines))  # the last line cut short by a kill: no number
    rows, bad = read_json_lines(path, keep=lambda row: row["step"] >= 0)
    assert rows == [{"step": 1}] and bad == [2, 4, 5]
    path.write_text("\n".join(lines) + "\n")  # a complete garbled last line: numbered
    assert read_json_lines(path)[1] == [2, 5, 6]
    path.write_bytes(b'{"step": 1}\n\xff\xfe{"step": 2}\n{"step": 3}\n')
    assert read_json_lines(path) == ([{"step": 1}, {"step": 3}], [2])
