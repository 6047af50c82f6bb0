"""Output folders of commands: one that a failed command created is removed again."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path


@contextlib.contextmanager
def removed_on_failure(out: str | Path) -> Iterator[None]:
    """Within the block, if it raises, delete what it created of the path to ``out``: the
    folders that did not exist before (innermost first, each only while empty) or, for a file,
    an empty ``out`` that did not exist. Nothing that existed before is touched."""
    out = Path(out)
    new = []
    path = out
    while not path.exists() and path.parent != path:
        new.append(path)
        path = path.parent
    try:
        yield
    except BaseException:
        for path in new:  # innermost first
            try:
                if path.is_dir() and not path.is_symlink():
                    path.rmdir()  # only an empty folder: OSError otherwise
                elif path.is_file() and path.stat().st_size == 0:
                    path.unlink()
            except OSError:
                break
        raise
