"""Every command in the README's bash blocks runs (tiny budgets), so the README cannot drift.

What is substituted (printed by ``-v`` runs through the test ids): ``--steps``, ``--envs``,
``--episodes``, ``--workers`` and a sweep's ``--seeds`` get the small values of
``doc_commands.TINY`` (``devlearn run`` and ``sweep`` get them added when missing, and a new
hand-regard run a short motor babbling: ``doc_commands.TINY_SETTINGS``); ``.venv/bin/``
prefixes are dropped (the test runs the installed ``devlearn`` of this interpreter); globs
expand in the test's folder. Skipped, by rule:
the set-up script and ``python -m pytest`` (CI runs them around this very test), ``source``, and
``devlearn bench`` (minutes of measurement; tests/bench/test_bench.py covers it). Any other
non-devlearn command fails the test, so a new kind of README command is noticed.
"""

from __future__ import annotations

import glob
import subprocess
from pathlib import Path

import doc_commands
import pytest

README = Path(__file__).resolve().parents[2] / "README.md"
SKIPPED = {
    ("bash", "scripts/setup.sh"): "set-up: CI's .ci/run runs it before the tests",
    ("python", "-m", "pytest"): "the test suite itself",
    ("source",): "activating the venv: the test already runs in it",
    ("devlearn", "bench"): "minutes of timing; tests/bench/test_bench.py covers bench",
}


def readme_commands() -> list[list[str]]:
    """Every command of the README's bash blocks, in order, ``.venv/bin/`` dropped."""
    out = []
    for block in doc_commands.blocks(README.read_text(), "bash"):
        for words in doc_commands.commands(block):
            out.append([w.removeprefix(".venv/bin/") for w in words])
    return out


def skip_reason(words: list[str]) -> str | None:
    for prefix, reason in SKIPPED.items():
        if tuple(words[: len(prefix)]) == prefix:
            return reason
    return None


def test_the_readme_has_the_commands_this_test_expects():
    commands = readme_commands()
    runnable = [w for w in commands if not skip_reason(w)]
    assert all(w[0] == "devlearn" for w in runnable), [w for w in runnable if w[0] != "devlearn"]
    names = {w[1] for w in runnable}
    assert {"run", "eval", "curve", "plugins", "info", "config"} <= names


def test_shrink_substitutes_tiny_budgets():
    words = doc_commands.shrink("devlearn run x --steps 2e5 --envs 8 --seed 1".split())
    assert words[3:] == [
        "run",
        "x",
        "--steps",
        "256",
        "--envs",
        "2",
        "--seed",
        "1",
        "--workers",
        "0",
    ]
    resume = doc_commands.shrink("devlearn run x --resume runs/a".split())
    assert "--steps" not in resume  # a resumed run keeps its own budget
    assert doc_commands.shrink(["devlearn", "eval", "--episodes", "100"])[-1] == "1"
    sweep = doc_commands.shrink("devlearn sweep x --grid a=1,2 --seeds 1,2,3".split())
    assert sweep[-8:] == ["--grid", "a=1,2", "--seeds", "1", "--envs", "2", "--episodes", "1"]
    # the grid stays, one seed; hand regard's babbling is a budget too, but not on a resume
    babbling = ["--set", "behavior.babbling_steps=2000"]
    assert doc_commands.shrink("devlearn run hand_regard --out r".split())[-2:] == babbling
    assert babbling[1] not in doc_commands.shrink("devlearn run hand_regard --resume r".split())
    assert babbling[1] not in doc_commands.shrink("devlearn eval hand_regard --policy zero".split())


@pytest.mark.slow
def test_every_readme_command_runs(tmp_path):
    ran = []
    for words in readme_commands():
        if skip_reason(words):
            continue
        words = doc_commands.shrink(words)
        expanded = []
        for word in words:
            matches = sorted(glob.glob(word, root_dir=tmp_path)) if "*" in word else []
            assert matches or "*" not in word, f"README glob {word} matches nothing after: {ran}"
            expanded += matches or [word]
        result = subprocess.run(expanded, cwd=tmp_path, capture_output=True, text=True, timeout=900)
        shown = " ".join(expanded[2:])
        assert result.returncode == 0, f"{shown}\n{result.stdout[-2000:]}\n{result.stderr[-2000:]}"
        ran.append(shown)
    assert len(ran) >= 8
