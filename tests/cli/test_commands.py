"""The command table (``devlearn/cli/commands.py``): each sub-command declared once, the
options several commands share declared once, and no command module imported to build the
parser."""

from __future__ import annotations

import argparse
import importlib
import json
import subprocess
import sys

from devlearn.cli import build_parser
from devlearn.cli.commands import COMMANDS, SHARED


def subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


def test_building_the_parser_imports_no_command_module():
    code = (
        "import json, sys\n"
        "from devlearn.cli import build_parser\n"
        "build_parser()\n"
        "print(json.dumps(sorted(m for m in sys.modules if m.startswith('devlearn.cli.'))))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout) == ["devlearn.cli.commands"]


def test_every_command_runs_a_module_with_run():
    assert [c.name for c in COMMANDS] == list(subparsers())
    for command in COMMANDS:
        assert callable(importlib.import_module(command.module).run), command.name
    assert next(c for c in COMMANDS if c.name == "eval").module == "devlearn.cli.evaluate"


def test_set_and_preset_are_one_option_wherever_they_are_taken():
    """``--set`` and ``--preset`` come from SHARED: the same destination, metavar and action in
    every command that takes them (run, eval, config, sweep); only their help differs."""
    takers = {"--set": set(), "--preset": set()}
    for name, parser in subparsers().items():
        for action in parser._actions:
            if action.option_strings and action.option_strings[0] in takers:
                flag = action.option_strings[0]
                takers[flag].add(name)
                assert (action.dest, action.metavar) == (
                    SHARED[flag].get("dest", flag[2:]),
                    SHARED[flag]["metavar"],
                ), (name, flag)
    assert takers == {
        "--set": {"run", "eval", "config", "sweep"},
        "--preset": {"run", "config", "sweep"},
    }
    for name in ("run", "config", "sweep"):
        args = subparsers()[name].parse_args(["b", "--set", "a=1", "--set", "b=2", "--preset", "p"])
        assert args.overrides == ["a=1", "b=2"] and args.preset == "p", name
