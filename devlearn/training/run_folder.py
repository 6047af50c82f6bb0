"""A run folder's start and metrics: a failed start leaves the folder as it was; a run started
``--from`` another run's checkpoint begins its metrics with that run's rows; a resumed run
forgets the rows logged after its checkpoint."""

from __future__ import annotations

import contextlib
import os
import shutil
from collections.abc import Iterator
from pathlib import Path

from devlearn.api.errors import UsageError
from devlearn.api.json_files import parse_json
from devlearn.files import write_text_atomically


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
def start_up(run_dir: Path, replace: bool, owner: bool) -> Iterator[None]:
    """Within the block, a failure puts ``run_dir`` back as it was: new entries are deleted
    (and the folder itself, if it was new), small files rewritten (config.json...) are restored.
    With ``replace`` the folder's entries are set aside first and deleted once the block
    succeeds. Only the ``owner`` (rank 0) touches the folder."""
    if not owner:
        yield
        return
    created = run_dir
    while not created.parent.exists() and created.parent != created:
        created = created.parent
    existed = run_dir.exists()
    before: dict[str, bytes | None] = {}
    aside = run_dir / f".devlearn-replaced-{os.getpid()}"
    if existed:
        for p in run_dir.iterdir():
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
            shutil.rmtree(created, ignore_errors=True)
            raise
        for p in run_dir.iterdir():
            if p != aside and (replace or p.name not in before):
                shutil.rmtree(p) if p.is_dir() and not p.is_symlink() else p.unlink()
            elif (saved := before.get(p.name)) is not None and p.is_file():
                if p.read_bytes() != saved:
                    p.write_bytes(saved)
        if replace:
            for name in before:
                os.replace(aside / name, run_dir / name)
            aside.rmdir()
        raise
    if replace:
        shutil.rmtree(aside, ignore_errors=True)
