"""devlearn's file writing: the one atomic writer, the checks of a place to write before any
work, and the lock that keeps a folder to one process.

A file is written beside its place and renamed over it, so that a crash at any moment (kill -9,
a full disk) leaves the previous file or the new one, never a partial file under the name.
Checkpoints, policy files, configs, evaluations, reports, pictures, sweep records and exported
policies all go through :func:`replaced_atomically`; it refuses to replace anything that is not
a regular file (a device such as /dev/null, a FIFO, a folder), which a rename would destroy.
Imports nothing of devlearn but its errors (any layer may use it) and no torch.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import re
import shutil
import stat
import tempfile
import threading
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import IO, BinaryIO

from devlearn.api.errors import UsageError

NAME_MAX = 255
"""Longest file name (bytes) of the common Linux file systems (a run folder's, a plugin's)."""
TEMPORARY = re.compile(r"^\..+\.tmp-\d+(-\d+)?$")
"""The names :func:`temporary_name` gives (``.NAME.tmp-PID`` or ``.NAME.tmp-PID-THREAD``)."""


class NotARegularFileError(UsageError):
    """The place to write exists and is not a regular file (a device, a FIFO, a socket or a
    folder): devlearn never replaces one."""


class InUseError(UsageError):
    """Another process holds the lock of what was to be written (a run folder, a sweep)."""


def temporary_name(path: Path) -> Path:
    """Where :func:`replaced_atomically` writes ``path`` first: ``.NAME.tmp-PID`` beside it (the
    thread's id added off the main thread, so that two threads never share one), a name
    ``devlearn.training.checkpoint.remove_temporaries`` recognises after a kill."""
    suffix = f"{os.getpid()}"
    if threading.current_thread() is not threading.main_thread():
        suffix += f"-{threading.get_ident()}"
    return path.with_name(f".{path.name}.tmp-{suffix}")


def fsync_dir(directory: Path) -> None:
    """Flush a folder's entries (a rename in it) to disk, where the system allows it."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _kind(mode: int) -> str:
    """What a file of ``mode`` (``st_mode``) is, in words."""
    for test, name in (
        (stat.S_ISDIR, "a folder"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return name
    return "not a regular file"


def check_replaceable(path: Path) -> None:
    """Refuse a ``path`` that exists and is not a regular file (followed through links): a
    device, a FIFO, a socket or a folder. A new path, or a regular file, passes.

    Raises:
        NotARegularFileError: One line naming the path and what it is.
    """
    try:
        mode = os.stat(path).st_mode
    except (FileNotFoundError, NotADirectoryError):
        return
    except OSError:
        return  # unreadable: the write itself says why
    if not stat.S_ISREG(mode):
        raise NotARegularFileError(
            f"cannot write {path}: it is {_kind(mode)}, not a regular file; give a file path"
        )


@contextlib.contextmanager
def replaced_atomically(path: Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; what the block writes there then replaces
    ``path`` in one rename (the folder synced). If the block or the rename fails, the temporary
    file is removed, ``path`` is unchanged and the error propagates as it came (callers word
    it for their users).

    Raises:
        NotARegularFileError: ``path`` exists and is not a regular file (checked before the
            block and again before the rename): it is left as it is.
    """
    path = Path(path)
    check_replaceable(path)
    tmp = temporary_name(path)
    try:
        yield tmp
        check_replaceable(path)  # made a device or FIFO while the block wrote
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    fsync_dir(path.parent)


def write_atomically(path: Path, write: Callable[[BinaryIO], object]) -> None:
    """Write ``path`` through :func:`replaced_atomically` with ``write(file)``, a binary file
    open on the temporary (e.g. ``lambda f: fig.savefig(f, format="png")``), synced before the
    rename.

    Raises:
        NotARegularFileError: ``path`` is a device, FIFO, socket or folder.
        OSError: It cannot be written (a full disk, no permission); ``path`` is unchanged.
        Exception: What ``write`` raises; ``path`` is unchanged.
    """
    with replaced_atomically(path) as tmp, open(tmp, "wb") as f:
        write(f)
        f.flush()
        os.fsync(f.fileno())


def write_bytes_atomically(path: Path, data: bytes | bytearray | memoryview) -> None:
    """Write ``data`` to ``path`` through :func:`replaced_atomically`, synced before the rename.

    Raises:
        NotARegularFileError: ``path`` is a device, FIFO, socket or folder.
        OSError: It cannot be written (a full disk, no permission); ``path`` is unchanged.
    """
    write_atomically(path, lambda f: f.write(data))


def copy_atomically(source: Path, path: Path) -> None:
    """Copy the file ``source``'s bytes to ``path`` through :func:`replaced_atomically`, synced
    before the rename (a published evaluation, a policy file).

    Raises:
        NotARegularFileError: ``path`` is a device, FIFO, socket or folder.
        OSError: ``source`` cannot be read or ``path`` written; ``path`` is unchanged.
    """
    with open(source, "rb") as src:
        write_atomically(path, lambda f: shutil.copyfileobj(src, f))


def write_text_atomically(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through :func:`replaced_atomically`, synced before the rename.

    Raises:
        NotARegularFileError: ``path`` is a device, FIFO, socket or folder.
        OSError: It cannot be written (a full disk, no permission); ``path`` is unchanged.
    """
    with replaced_atomically(path) as tmp, open(tmp, "w") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())


def unwritable(folder: Path) -> str | None:
    """Why no file can be created in ``folder`` (tried: a file made and deleted), or None."""
    try:
        fd, probe = tempfile.mkstemp(prefix=".devlearn-probe-", dir=folder)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        return str(exc.strerror or exc)
    return None


def check_out_file(
    path: Path, option: str = "--out", suffixes: Sequence[str] = (), parents: bool = False
) -> None:
    """Refuse a place to write a file before any work is done: a folder, something that is
    not a regular file (:func:`check_replaceable`), a name without one of ``suffixes`` (when
    given; compared lower-case), a missing folder (unless ``parents``: then the nearest folder
    that exists) or one where no file can be created.

    Args:
        path: The file to write.
        option: How the user named it, for the message (``--out``, ``--video``).
        suffixes: The file types that can be written there (``.png``), or empty: any.
        parents: Missing folders on the way will be made (the nearest existing one is
            checked).
    Raises:
        UsageError: One line naming the problem and what is valid (a
            :class:`NotARegularFileError` for a device or FIFO).
    """
    path = Path(path)
    try:
        if path.is_dir():
            raise NotARegularFileError(f"{option} {path} is a folder; give the file to write")
        check_replaceable(path)
        if suffixes and path.suffix.lower() not in suffixes:
            raise UsageError(
                f"{option} {path}: cannot write a '{path.suffix or '(no extension)'}' file; "
                f"valid: {', '.join(suffixes)}"
            )
        folder = path.parent
        while parents and not folder.exists() and folder.parent != folder:
            folder = folder.parent
        if not folder.is_dir():
            what = "is not a folder" if folder.exists() else "does not exist"
            raise UsageError(f"cannot write {path}: {folder} {what}")
        os.stat(path)  # a name too long for the system
    except FileNotFoundError:
        pass
    except OSError as exc:
        raise UsageError(f"cannot write {path}: {exc.strerror or exc}") from None
    reason = unwritable(folder)
    if reason:
        raise UsageError(f"cannot write {path}: cannot create files in {folder} ({reason})")


def lock_exclusively(path: Path, what: str) -> IO[str]:
    """Open ``path`` (made if missing) and hold an exclusive lock on it (``fcntl.flock``), with
    ``pid N`` (this process) written in it; return the open file.

    Closing the file releases the lock, and so does the end of the process, however it ends
    (kill -9 included); a child process given the descriptor holds it too. A lock file deleted
    or replaced while this process waited for it is opened again, so two processes never hold
    locks on two files of one name.

    Args:
        path: The lock file.
        what: What it keeps to one process, for the message (``run folder runs/a``).
    Raises:
        InUseError: Another process holds it: ``WHAT is in use by pid N``.
        OSError: The lock file cannot be made.
    """
    while True:
        lock = open(path, "a+")
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            lock.seek(0)
            holder = lock.read().strip() or "another process"
            lock.close()
            raise InUseError(f"{what} is in use by {holder}") from None
        try:
            same = os.path.samestat(os.fstat(lock.fileno()), os.stat(path))
        except OSError:
            same = False
        if same:
            break
        lock.close()  # deleted or replaced before we held it: lock the file there now
    lock.seek(0)
    lock.truncate()
    lock.write(f"pid {os.getpid()}\n")
    lock.flush()
    return lock


def check_unlocked(path: Path, what: str) -> None:
    """Refuse at once if a process holds the lock ``path`` (:func:`lock_exclusively`): a probe
    that writes nothing (a missing lock file is not made) and holds nothing after it returns,
    for a command to fail before any work rather than when it takes the lock.

    Raises:
        InUseError: ``WHAT is in use by pid N``.
    """
    try:
        lock = open(path)
    except OSError:
        return  # no lock file: nobody holds it
    with lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = lock.read().strip() or "another process"
            raise InUseError(f"{what} is in use by {holder}") from None


def release_lock(lock: IO[str], path: Path) -> None:
    """Delete the lock file ``path`` if it is still the one ``lock`` holds, then release it
    (a process that opened it meanwhile opens it again: :func:`lock_exclusively`)."""
    with contextlib.suppress(OSError):
        if os.path.samestat(os.fstat(lock.fileno()), os.stat(path)):
            os.unlink(path)
    lock.close()
