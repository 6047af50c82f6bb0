"""devlearn's one atomic writer (devlearn/files.py): the previous file or the new one, never a
partial file, and no temporary left behind."""

from __future__ import annotations

import threading

import pytest

from devlearn.files import replaced_atomically, temporary_name, write_text_atomically
from devlearn.training.checkpoint import remove_temporaries


def test_a_failed_write_leaves_the_previous_file_and_no_temporary(tmp_path):
    path = tmp_path / "metrics.jsonl"
    write_text_atomically(path, "old\n")
    with pytest.raises(RuntimeError, match="cut"), replaced_atomically(path) as tmp:
        tmp.write_text("half")
        raise RuntimeError("cut short")
    assert path.read_text() == "old\n"
    assert [p.name for p in tmp_path.iterdir()] == ["metrics.jsonl"]
    write_text_atomically(path, "new\n")
    assert path.read_text() == "new\n" and len(list(tmp_path.iterdir())) == 1


def test_threads_write_through_their_own_temporaries(tmp_path):
    path = tmp_path / "checkpoint_64.pt"
    names = [temporary_name(path)]
    thread = threading.Thread(target=lambda: names.append(temporary_name(path)))
    thread.start()
    thread.join()
    assert names[0] != names[1]
    # either is a temporary a killed run leaves, which a resumed run removes
    for name in names:
        name.touch()
    path.touch()
    stale = [p for p in tmp_path.iterdir() if p.name.startswith(".")]
    assert len(stale) == 2 and sorted(remove_temporaries(tmp_path)) == sorted(stale)
