"""The options several commands share, declared once: the behaviour argument, ``--set`` and
``--preset`` (each command gives only the help text that says what they do there)."""

from __future__ import annotations

import argparse

SET_HELP = "override a config field, e.g. ppo.learning_rate=3e-4 (repeatable)"
PRESET_HELP = (
    "start from a named set of the behaviour's values (e.g. paper); "
    "`devlearn config BEHAVIOR` lists them"
)


def add_behavior(p: argparse.ArgumentParser) -> None:
    """The positional behaviour name."""
    p.add_argument("behavior", help="behaviour name (see `devlearn plugins`)")


def add_overrides(p: argparse.ArgumentParser, help: str = SET_HELP) -> None:
    """``--set KEY=VALUE`` (repeatable) into ``args.overrides``."""
    p.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE", help=help
    )


def add_preset(p: argparse.ArgumentParser, help: str = PRESET_HELP) -> None:
    """``--preset NAME`` into ``args.preset``."""
    p.add_argument("--preset", metavar="NAME", help=help)
