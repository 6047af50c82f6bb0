"""Commands from the docs' bash blocks, shrunk to tiny budgets so tests can run them."""

from __future__ import annotations

import re
import shlex
import sys

TINY = {"--steps": "256", "--envs": "2", "--episodes": "1", "--workers": "0", "--seeds": "1"}
"""Option -> the small value a test substitutes. A sweep keeps its grid (each variant still
trains, evaluates and reports) but runs one seed."""
ADDED = {"run": ("--steps", "--envs", "--workers"), "sweep": ("--envs", "--episodes")}
"""Options of :data:`TINY` added to a command that lacks them (a resumed run keeps its
``--steps``): a sweep's runs would otherwise train 8 environments and evaluate 10 episodes."""
TINY_SETTINGS = {"hand_regard": ("behavior.babbling_steps=2000",)}
"""``--set`` values added to a new ``devlearn run`` of a behaviour: hand regard's motor
babbling (10,000 rendered steps by default) is a budget too; 2,000 steps still find the
hands (and the calibration's fixed 2,000 held-out steps still run)."""


def blocks(markdown: str, language: str) -> list[str]:
    """The bodies of the ```language fenced blocks, in order."""
    return re.findall(rf"^```{language}\n(.*?)^```", markdown, flags=re.S | re.M)


def commands(block: str) -> list[list[str]]:
    """A bash block's commands as argument lists (comments dropped, ``&&`` chains split)."""
    out: list[list[str]] = []
    for line in block.replace("\\\n", " ").splitlines():
        words = shlex.split(line, comments=True)
        while words:
            cut = words.index("&&") if "&&" in words else len(words)
            if words[:cut]:
                out.append(words[:cut])
            words = words[cut + 1 :]
    return out


def shrink(words: list[str]) -> list[str]:
    """``devlearn run/eval/...`` with :data:`TINY` budgets; other commands unchanged."""
    if not words or words[0].rsplit("/", 1)[-1] != "devlearn":
        return list(words)
    words = [sys.executable, "-m", "devlearn.cli", *words[1:]]
    command = words[3] if len(words) > 3 else ""
    for option, value in TINY.items():
        if option in words:
            words[words.index(option) + 1] = value
        elif option in ADDED.get(command, ()):
            if option != "--steps" or "--resume" not in words:
                words += [option, value]
    if command == "run" and "--resume" not in words and len(words) > 4:
        for setting in TINY_SETTINGS.get(words[4], ()):
            words += ["--set", setting]
    return words
