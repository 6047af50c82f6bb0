"""``devlearn picture body-map|eyes|growth --out PATH``: pictures of the infant's body map, its
view and its body at 0, 6, 12, 18 and 24 months."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Callable

    import numpy as np

    from devlearn.plugins import PluginRegistry


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Draw the picture, write it (atomically, in the type its extension names) and print its
    path (``registry`` is unused). The path is checked before anything is drawn."""
    del registry
    from pathlib import Path

    from devlearn.api.errors import UsageError
    from devlearn.env.rendering import require_rendering
    from devlearn.files import check_out_file, write_bytes_atomically
    from devlearn.infant.pictures import (
        IMAGE_SUFFIXES,
        body_map_picture,
        encode_picture,
        eyes_picture,
        growth_picture,
    )

    draw: dict[str, Callable[[], np.ndarray]] = {
        "body-map": body_map_picture,
        "eyes": eyes_picture,
        "growth": growth_picture,
    }
    out = Path(args.out)
    check_out_file(out, suffixes=IMAGE_SUFFIXES, parents=True)
    require_rendering(f"devlearn picture {args.what}")  # every picture is a render
    data = encode_picture(draw[args.what](), out.suffix.lower())
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        write_bytes_atomically(out, data)
    except OSError as exc:
        raise UsageError(f"cannot write {out}: {exc.strerror or exc}") from None
    print(out)
    return 0
