"""devlearn's one atomic writer (devlearn/files.py): the previous file or the new one, never a
partial file, and no temporary left behind."""

from __future__ import annotations

import os
import stat
import subprocess
import sys
import threading

import pytest

from devlearn.files import (
    copy_atomically,
    replaced_atomically,
    temporary_name,
    write_text_atomically,
)
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


def test_a_fifo_or_a_device_is_never_replaced(tmp_path):
    """Issue #55: the rename put a regular file in place of a device node or FIFO (as root,
    ``--out /dev/null`` destroyed /dev/null)."""
    from devlearn.api.errors import UsageError

    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    targets = {fifo: "a FIFO", tmp_path: "a folder"}
    if os.geteuid() == 0:  # a null device of our own, never /dev/null itself
        node = tmp_path / "null"
        os.mknod(node, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
        targets[node] = "a character device"
    for path, kind in targets.items():
        with pytest.raises(UsageError, match=f"cannot write {path}: it is {kind}, not a regular"):
            write_text_atomically(path, "text\n")
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    if os.geteuid() == 0:
        assert stat.S_ISCHR(os.lstat(tmp_path / "null").st_mode)
    assert not [p for p in tmp_path.iterdir() if ".tmp-" in p.name]  # nothing written
    for path in targets:
        if path != tmp_path:
            path.unlink()  # no FIFO left for a later test's folder scan to block on


def test_a_target_made_a_fifo_while_the_block_wrote_is_left_alone(tmp_path):
    from devlearn.api.errors import UsageError

    path = tmp_path / "record.json"
    with pytest.raises(UsageError, match="it is a FIFO"), replaced_atomically(path) as tmp:
        tmp.write_text("{}")
        os.mkfifo(path)
    assert stat.S_ISFIFO(os.lstat(path).st_mode) and sorted(tmp_path.iterdir()) == [path]
    path.unlink()


def test_a_copy_is_atomic_and_never_replaces_a_fifo(tmp_path):
    """What ``devlearn experiment publish`` copies (evaluations, configs, a policy file)."""
    from devlearn.api.errors import UsageError

    source, copy = tmp_path / "source.json", tmp_path / "copy.json"  # no eval.json: the
    # report test scans the folders beside its own for */eval.json
    source.write_bytes(b'{"a": 1}' * 10_000)
    copy_atomically(source, copy)
    assert copy.read_bytes() == source.read_bytes()
    fifo = tmp_path / "fifo.json"
    os.mkfifo(fifo)
    with pytest.raises(UsageError, match="it is a FIFO"):
        copy_atomically(source, fifo)
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    fifo.unlink()
    with pytest.raises(FileNotFoundError):
        copy_atomically(tmp_path / "missing", copy)
    assert copy.read_bytes() == source.read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["copy.json", "source.json"]


HOLD = """
import sys, time
from pathlib import Path
from devlearn.files import lock_exclusively
lock = lock_exclusively(Path(sys.argv[1]), "the folder")
print("held", flush=True)
time.sleep(600)
"""


def test_a_lock_is_one_process_s_until_it_ends_however_it_ends(tmp_path):
    """The one lock of run folders and sweeps (:func:`devlearn.files.lock_exclusively`)."""
    from devlearn.files import InUseError, check_unlocked, lock_exclusively, release_lock

    path = tmp_path / ".run.lock"
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD, str(path)], stdout=subprocess.PIPE, text=True
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
        with pytest.raises(InUseError, match=f"^the folder is in use by pid {holder.pid}$"):
            lock_exclusively(path, "the folder")
        with pytest.raises(InUseError, match=f"^the folder is in use by pid {holder.pid}$"):
            check_unlocked(path, "the folder")
    finally:
        holder.kill()  # kill -9: the lock ends with the process
        holder.wait(timeout=60)
    check_unlocked(path, "the folder")
    lock = lock_exclusively(path, "the folder")
    assert path.read_text() == f"pid {os.getpid()}\n"
    release_lock(lock, path)
    assert not path.exists()
    check_unlocked(path, "the folder")  # no lock file: free, and none is made
    assert not path.exists()
