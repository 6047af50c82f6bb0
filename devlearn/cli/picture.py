"""``devlearn picture body-map|eyes|growth --out PATH``: pictures of the infant's body map, its
view and its body at 0, 6, 12, 18 and 24 months."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Callable
    from pathlib import Path

    from devlearn.plugins import PluginRegistry

PICTURES = ("body-map", "eyes", "growth")


def add_parser(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> list[str]:
    """Register the ``picture`` sub-command."""
    p = subparsers.add_parser(
        "picture",
        help="draw the 68-region body map, what the two eyes see, or the body at 0-24 months (PNG)",
    )
    p.add_argument(
        "what",
        choices=PICTURES,
        help="body-map: skin regions; eyes: both eye images; growth: the infant at 0, 6, 12, 18 "
        "and 24 months side by side, at one scale",
    )
    p.add_argument("--out", required=True, metavar="PATH", help="PNG file to write")
    return ["picture"]


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Write the picture and print its path (``registry`` is unused)."""
    del registry
    from devlearn.infant.pictures import body_map_picture, eyes_picture, growth_picture

    draw: dict[str, Callable[[str], Path]] = {
        "body-map": body_map_picture,
        "eyes": eyes_picture,
        "growth": growth_picture,
    }
    print(draw[args.what](args.out))
    return 0
