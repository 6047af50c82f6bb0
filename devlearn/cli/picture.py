"""``devlearn picture body-map|eyes|growth --out PATH``: pictures of the infant's body map, its
view and its body at 0, 6, 12, 18 and 24 months."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Callable
    from pathlib import Path

    from devlearn.plugins import PluginRegistry


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Write the picture and print its path (``registry`` is unused)."""
    del registry
    from devlearn.env.rendering import require_rendering

    require_rendering(f"devlearn picture {args.what}")  # every picture is a render
    from devlearn.infant.pictures import body_map_picture, eyes_picture, growth_picture

    draw: dict[str, Callable[[str], Path]] = {
        "body-map": body_map_picture,
        "eyes": eyes_picture,
        "growth": growth_picture,
    }
    print(draw[args.what](args.out))
    return 0
