"""devlearn's one atomic writer: a file is written beside its place and renamed over it, so that
a crash at any moment (kill -9, a full disk) leaves the previous file or the new one, never a
partial file under the name. Checkpoints, policy files, metrics, sweep records and exported
policies all go through :func:`replaced_atomically`. Imports nothing of devlearn (any layer may
use it) and no torch."""

from __future__ import annotations

import contextlib
import os
import threading
from collections.abc import Iterator
from pathlib import Path


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


@contextlib.contextmanager
def replaced_atomically(path: Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; what the block writes there then replaces
    ``path`` in one rename (the folder synced). If the block or the rename fails, the temporary
    file is removed, ``path`` is unchanged and the error propagates as it came (callers word
    it for their users).
    """
    path = Path(path)
    tmp = temporary_name(path)
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    fsync_dir(path.parent)


def write_text_atomically(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through :func:`replaced_atomically`, synced before the rename.

    Raises:
        OSError: It cannot be written; ``path`` is unchanged.
    """
    with replaced_atomically(path) as tmp, open(tmp, "w") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
