"""A run folder's lock, start and metrics: one process trains in a folder at a time; a failed
start leaves the folder as it was; a run started ``--from`` another run's checkpoint begins its
metrics with that run's rows; a resumed run forgets the rows logged after its checkpoint."""

from __future__ import annotations

import contextlib
import os
import shutil
from collections.abc import Iterator
from pathlib import Path

from devlearn.api.errors import UsageError
from devlearn.api.json_files import parse_json
from devlearn.files import (
    InUseError,
    check_replaceable,
    check_unlocked,
    lock_exclusively,
    release_lock,
    write_bytes_atomically,
    write_text_atomically,
)

LOCK_FILE = ".run.lock"
"""The run folder's lock file (:func:`locked`), ``pid N`` of the process training there."""
WRITTEN = ("config.json", "metrics.jsonl", "checkpoint_latest.pt", "networks.txt")
"""Files a run writes in its folder under fixed names (:func:`check_run_files`)."""


def check_run_files(run_dir: Path) -> None:
    """Refuse a run folder where a file the run writes (:data:`WRITTEN`) exists and is not a
    regular file: a device or FIFO is never replaced (and a FIFO would hang the run).

    Raises:
        UsageError: One line naming the file and what it is.
    """
    for name in WRITTEN:
        check_replaceable(Path(run_dir) / name)


def check_not_in_use(run_dir: Path) -> None:
    """Refuse ``run_dir`` before any work if another process trains in it (holds the lock of
    :func:`locked`); writes nothing.

    Raises:
        UsageError: ``RUN is in use by pid N``.
    """
    check_unlocked(Path(run_dir) / LOCK_FILE, str(run_dir))


@contextlib.contextmanager
def locked(run_dir: Path, owner: bool = True) -> Iterator[Path | None]:
    """Within the block ``run_dir`` is this process's alone: it holds the lock on
    ``run_dir/.run.lock`` (:func:`devlearn.files.lock_exclusively`), so a second ``devlearn
    run`` on the folder (``--resume``, ``--out --force``) is refused instead of writing into it.
    The lock ends with the block (its file deleted), or with the process however it ends
    (kill -9 included: the file stays, unlocked). Only the ``owner`` (rank 0) locks.

    Yields:
        The outermost folder made for the lock (the folder did not exist), to delete again if
        the start fails (:func:`start_up`), or None.
    Raises:
        UsageError: ``RUN is in use by pid N`` (:class:`~devlearn.files.InUseError`), or the
            folder cannot be made.
    """
    if not owner:
        yield None
        return
    created = None
    path = Path(run_dir)
    while not path.exists() and path.parent != path:
        created, path = path, path.parent
    try:
        run_dir.mkdir(parents=True, exist_ok=True)
        lock = lock_exclusively(run_dir / LOCK_FILE, str(run_dir))
    except InUseError:
        raise  # the holder's folder: nothing here is ours to remove
    except OSError as exc:
        if created is not None:
            shutil.rmtree(created, ignore_errors=True)
        raise UsageError(f"cannot write to {run_dir}: {exc.strerror or exc}") from None
    try:
        yield created
    finally:
        release_lock(lock, run_dir / LOCK_FILE)


def forget_metrics_after(path: Path, step: int) -> None:
    """Drop ``metrics.jsonl`` rows past ``step`` (atomically): a killed run may have logged
    iterations after its last checkpoint, and the resumed run redoes (and logs) them again."""
    if not path.exists():
        return
    kept = []
    for line in path.read_text(errors="replace").splitlines():
        try:
            if parse_json(line, "a metrics row")["step"] <= step:
                kept.append(line)
        except (UsageError, KeyError, TypeError):
            pass  # a line cut short by the kill
    write_text_atomically(path, "".join(line + "\n" for line in kept))


def copy_metrics(source_dir: Path, run_dir: Path, step: int) -> None:
    """Start ``run_dir``'s metrics.jsonl with the source run's rows up to ``step``."""
    source = source_dir / "metrics.jsonl"
    if source.is_file() and source.resolve() != (run_dir / "metrics.jsonl").resolve():
        shutil.copyfile(source, run_dir / "metrics.jsonl")
        forget_metrics_after(run_dir / "metrics.jsonl", step)


_SMALL_FILE = 1 << 20  # files up to this size are restored byte for byte after a failed start


@contextlib.contextmanager
def start_up(
    run_dir: Path, replace: bool, owner: bool, created: Path | None = None
) -> Iterator[None]:
    """Within the block, a failure puts ``run_dir`` back as it was: new entries are deleted
    (and ``created``, the outermost folder :func:`locked` made for this start, if any), small
    files rewritten (config.json...) are restored. With ``replace`` the folder's entries are set
    aside first and deleted once the block succeeds. The lock file is left to :func:`locked`.
    Only the ``owner`` (rank 0) touches the folder."""
    if not owner:
        yield
        return
    existed = created is None and run_dir.exists()
    before: dict[str, bytes | None] = {}
    aside = run_dir / f".devlearn-replaced-{os.getpid()}"
    if existed:
        for p in run_dir.iterdir():
            if p.name == LOCK_FILE:
                continue
            small = p.is_file() and p.stat().st_size <= _SMALL_FILE
            before[p.name] = p.read_bytes() if small else None
        if replace:
            aside.mkdir()
            for name in before:
                os.replace(run_dir / name, aside / name)
    try:
        yield
    except BaseException:
        if not existed:
            shutil.rmtree(created or run_dir, ignore_errors=True)
            raise
        for p in run_dir.iterdir():
            if p.name == LOCK_FILE:
                continue
            if p != aside and (replace or p.name not in before):
                shutil.rmtree(p) if p.is_dir() and not p.is_symlink() else p.unlink()
            elif (saved := before.get(p.name)) is not None and p.is_file():
                if p.read_bytes() != saved:
                    write_bytes_atomically(p, saved)
        if replace:
            for name in before:
                os.replace(aside / name, run_dir / name)
            aside.rmdir()
        raise
    if replace:
        shutil.rmtree(aside, ignore_errors=True)
