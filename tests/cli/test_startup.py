"""Start-up: commands that neither train nor evaluate import no torch (nor rsl-rl, MuJoCo...).

Measured, not timed: ``devlearn bench`` reports each command's start-up (``startup_*_s``); here
the modules a command loaded are checked, which does not depend on the machine's load.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

HEAVY = ("torch", "rsl_rl", "mujoco", "dm_control", "numba", "matplotlib")
SCRIPT = """
import json, sys
from devlearn.cli import main
try:
    main(sys.argv[1:])
except SystemExit:
    pass
print(json.dumps(sorted(m for m in {heavy} if m in sys.modules)), file=sys.stderr)
"""


def heavy_modules(*args: str) -> list[str]:
    """The heavy modules a command loaded, every installed plugin enabled."""
    env = {**os.environ, "DEVLEARN_DISABLE_PLUGINS": ""}
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT.format(heavy=HEAVY), *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    return json.loads(done.stderr.strip().splitlines()[-1])


@pytest.mark.parametrize("args", [["--help"], ["run", "--help"], ["eval", "--help"], []])
def test_help_imports_nothing_heavy(args):
    assert heavy_modules(*args) == []


@pytest.mark.parametrize(
    "args",
    [
        ["plugins"],
        ["plugins", "--json"],
        ["config", "self_touch"],
        ["config", "hand_regard", "--preset", "paper"],
        ["config", "self_touch", "--set", "curiosity=rnd,forward_model", "--json"],
    ],
)
def test_plugins_and_config_import_nothing_heavy(args):
    # the built-in plugins (self_touch, hand_regard, curiosity) load torch, rsl-rl and numba
    # only to build networks, learned rewards or to step: registering them loads none of it
    assert heavy_modules(*args) == []


@pytest.mark.parametrize("behavior", ["self_touch", "hand_regard"])
def test_info_needs_the_body_but_not_torch(behavior):
    loaded = heavy_modules("info", behavior)
    assert "mujoco" in loaded  # the command did build the body
    assert "torch" not in loaded and "rsl_rl" not in loaded and "matplotlib" not in loaded
    # describing compiles nothing: the senses' numpy references give the same shapes
    assert "numba" not in loaded


def test_the_public_api_loads_on_first_use():
    done = subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys, devlearn; from devlearn import Behavior, IntrinsicReward, hookimpl; "
            "import devlearn.config.run_config, devlearn.config.checks; "
            "light = 'torch' not in sys.modules; "
            "from devlearn import MLPEncoder; from devlearn.training import train; "
            "from devlearn.evaluation.evaluate import Evaluation; "
            "print(light, 'torch' in sys.modules, callable(train), callable(Evaluation))",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.stdout.split() == ["True", "True", "True", "True"], done.stderr
