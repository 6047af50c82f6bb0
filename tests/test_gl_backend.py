"""``MUJOCO_GL`` (issue #55, fault 10): a value MuJoCo does not know stops only what renders,
with one line naming the variable and the valid values; self-touch, which never renders, runs.
mujoco reads the variable when first imported, so each case runs in a fresh interpreter."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from devlearn.gl_backend import BACKENDS, importable, rendering_problem

BOGUS = {**os.environ, "MUJOCO_GL": "bogus"}


def python(script: str, env: dict[str, str] = BOGUS) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=300
    )


def devlearn(*args: str, cwd: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "devlearn.cli", *args],
        env=BOGUS,
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=600,
    )


def test_each_value_renders_is_off_or_is_unknown(monkeypatch):
    for value in (*BACKENDS, "", "1", "on"):
        monkeypatch.setenv("MUJOCO_GL", value)
        assert rendering_problem() is None
    monkeypatch.delenv("MUJOCO_GL")
    assert rendering_problem() is None
    monkeypatch.setenv("MUJOCO_GL", "off")
    assert rendering_problem() == (
        "MUJOCO_GL=off turns rendering off, and this renders; set it to egl, osmesa or glfw"
    )
    for value in ("bogus", "EGL", "glx"):  # glx: mujoco takes it, dm_control does not
        monkeypatch.setenv("MUJOCO_GL", value)
        assert rendering_problem() == (
            f"MUJOCO_GL={value!r} is not an OpenGL backend MuJoCo knows; set it to egl, osmesa "
            "or glfw (egl: headless, the default), or unset it"
        )
        with importable():  # imported with rendering off, then given back
            assert os.environ["MUJOCO_GL"] == "disable"
        assert os.environ["MUJOCO_GL"] == value


def test_an_infant_that_renders_nothing_works_and_one_that_renders_is_one_line():
    script = """
import numpy as np
from devlearn.api.errors import UsageError
from devlearn.env.behavior_env import build_default_infant
from devlearn.infant import build_infant

infant = build_infant("crib", senses=("touch", "proprioception"))
infant.reset(np.random.default_rng(0))
for _ in range(3):
    infant.step(np.zeros(infant.action_dim))
print("stepped")
try:
    build_default_infant("crib", senses=("proprioception", "eyes"))
except UsageError as err:
    print("refused:", err)
try:
    infant.render_view()
except RuntimeError as err:
    print("view:", err)
"""
    done = python(script)
    assert done.returncode == 0, done.stderr[-3000:]
    lines = done.stdout.splitlines()
    problem = "MUJOCO_GL='bogus' is not an OpenGL backend MuJoCo knows; set it to egl"
    assert lines[0] == "stepped"
    assert lines[1].startswith(f"refused: the infant (the infant's eyes) needs rendering: {problem}")
    assert lines[2].startswith(f"view: {problem}") and len(lines) == 3


@pytest.mark.slow
def test_the_cli_runs_what_never_renders_and_refuses_what_does(tmp_path):
    """Was a 44-line traceback from ``import mujoco`` for any command that built an infant."""
    run = devlearn("run", "self_touch", "--steps", "64", "--envs", "1", "--workers", "0",
                   "--out", str(tmp_path / "touch"), cwd=str(tmp_path))  # fmt: skip
    assert run.returncode == 0, run.stderr[-3000:]
    assert (tmp_path / "touch" / "checkpoint_latest.pt").is_file()
    refusals = [
        ("run", "hand_regard", "--steps", "64", "--envs", "2", "--workers", "2",
         "--out", str(tmp_path / "eyes")),
        ("eval", "self_touch", "--policy", "zero", "--episodes", "1",
         "--video", str(tmp_path / "v.mp4"), "--out", str(tmp_path / "video")),
        ("picture", "eyes", "--out", str(tmp_path / "eyes.png")),
    ]  # fmt: skip
    for argv in refusals:
        done = devlearn(*argv, cwd=str(tmp_path))
        assert done.returncode == 2, (argv, done.stderr[-3000:])
        assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr
        assert "needs rendering: MUJOCO_GL='bogus' is not an OpenGL backend" in done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["touch"]  # nothing else written
