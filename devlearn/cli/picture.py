"""``devlearn picture body-map|eyes --out PATH``: pictures of the infant's body map and view."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry

PICTURES = ("body-map", "eyes")


def add_parser(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> list[str]:
    """Register the ``picture`` sub-command."""
    p = subparsers.add_parser(
        "picture", help="draw the 68-region body map or what the two eyes see (PNG)"
    )
    p.add_argument("what", choices=PICTURES, help="body-map: skin regions; eyes: both eye images")
    p.add_argument("--out", required=True, metavar="PATH", help="PNG file to write")
    return ["picture"]


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Write the picture and print its path (``registry`` is unused)."""
    del registry
    from devlearn.infant.pictures import body_map_picture, eyes_picture

    draw = body_map_picture if args.what == "body-map" else eyes_picture
    print(draw(args.out))
    return 0
