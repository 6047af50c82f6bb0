"""The ``devlearn`` command line: the sub-commands declared in ``commands.py``, each run by its
module in this package."""

from __future__ import annotations

import argparse
import importlib
import sys
from typing import NoReturn

from devlearn.api.errors import UsageError
from devlearn.cli.commands import COMMANDS, Command, OneOf


class OneLineParser(argparse.ArgumentParser):
    """argparse with devlearn's errors: one line naming the problem and where the help is,
    not the whole usage block (a bad --start printed 7 lines)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"devlearn: error: {message} (see `{self.prog} --help`)\n")


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser of every sub-command in ``COMMANDS`` (importing none of
    their modules)."""
    parser = OneLineParser(
        prog="devlearn",
        description="Developmental RL: a simulated infant learns body skills from curiosity.",
    )
    parser.add_argument(
        "--disable-plugin",
        action="append",
        default=[],
        metavar="NAME",
        help="skip a plugin for this command (repeatable; see also DEVLEARN_DISABLE_PLUGINS)",
    )
    subparsers = parser.add_subparsers(
        dest="command", metavar="COMMAND", parser_class=OneLineParser
    )
    for command in COMMANDS:
        _add_command(subparsers, command)
    return parser


def _add_command(subparsers: argparse._SubParsersAction, command: Command) -> None:
    """One sub-command's parser, with its options (and its actions' parsers)."""
    p = subparsers.add_parser(command.name, help=command.help, description=command.description)
    for entry in command.options:
        if isinstance(entry, OneOf):
            group = p.add_mutually_exclusive_group(required=entry.required)
            for option in entry.options:
                group.add_argument(*option.flags, **option.kwargs)
        else:
            p.add_argument(*entry.flags, **entry.kwargs)
    if command.actions:
        actions = p.add_subparsers(
            dest="action", metavar="ACTION", parser_class=OneLineParser, required=True
        )
        for action in command.actions:
            _add_command(actions, action)


def follow_parent() -> None:
    """When started by a sweep (``DEVLEARN_PARENT_PID`` set), ask Linux for SIGTERM when that
    process dies (as a Ctrl-C: a run saves a checkpoint), and stop at once if it already has;
    elsewhere, or without ``prctl``, nothing."""
    import os
    import signal

    parent = os.environ.pop("DEVLEARN_PARENT_PID", "")
    if not parent.isdigit():
        return
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, int(signal.SIGTERM))  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        return
    if os.getppid() != int(parent):  # the sweep died before prctl took effect
        raise SystemExit(130)


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; return the exit code (2 for bad input, with a one-line message)."""
    follow_parent()
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 2
    from devlearn.plugins import PluginRegistry, disabled_plugins

    registry = PluginRegistry(disabled=disabled_plugins() | set(args.disable_plugin))
    for error in registry.errors:
        print(f"devlearn: warning: {error}", file=sys.stderr)
    try:
        unknown = [name for name in args.disable_plugin if name not in registry.plugins]
        if unknown:  # a typo would leave the plugin it meant enabled, silently
            installed = ", ".join(sorted(registry.plugins)) or "none"
            raise UsageError(
                f"--disable-plugin {unknown[0]}: no such plugin; installed: {installed}"
            )
        command = next(c for c in COMMANDS if c.name == args.command)
        return int(importlib.import_module(command.module).run(args, registry) or 0)
    except UsageError as exc:
        print(f"devlearn: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("devlearn: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
