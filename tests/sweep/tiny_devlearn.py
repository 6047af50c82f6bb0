"""``devlearn`` with the tiny test behaviours and the fake infant, for sweep tests.

Sweeps start ``devlearn run`` and ``devlearn eval`` as subprocesses; the tests give this script
as the sweep's launcher (``python tiny_devlearn.py run tiny ...``) so those subprocesses train
the tiny behaviour in seconds. Behaviours: ``tiny``, ``other`` and ``fragile`` (tiny, but its
reward raises once ``behavior.break_after`` steps are done, 0 never: a run that fails).
"""

from __future__ import annotations

import functools
import sys
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "env"))

from tiny_behaviors import OtherBehavior  # noqa: E402

from devlearn.testing import registry_for  # noqa: E402
from devlearn.testing.fake_infant import (  # noqa: E402
    Reach,
    TinyBehavior,
    TinyConfig,
    fake_infant_factory,
)

EPISODE_STEPS = 10


@dataclass
class FragileConfig(TinyConfig):
    """Options of the fragile test behaviour."""

    break_after: int = 0
    """Reward calls per environment after which the reward raises (0: never)."""


class BreakingReach(Reach):
    """Tiny's reach term, raising RuntimeError after ``break_after`` calls (0: never)."""

    def __init__(self, target: float, break_after: int) -> None:
        super().__init__(target)
        self.break_after = break_after
        self.calls = 0

    def __call__(self, ctx):
        self.calls += 1
        if self.break_after and self.calls > self.break_after:
            raise RuntimeError(f"fragile reward broke after {self.break_after} steps")
        return super().__call__(ctx)


class FragileBehavior(TinyBehavior):
    """Tiny, with a reward that can be told to break."""

    name = "fragile"
    config_class = FragileConfig

    def reward_terms(self):
        terms = super().reward_terms()
        terms[0] = BreakingReach(self.config.target, self.config.break_after)
        return terms


def registry():
    """A registry of tiny, other and fragile."""
    return registry_for(TinyBehavior, OtherBehavior, FragileBehavior)


def install(monkeypatch=None) -> None:
    """Make devlearn's CLI use :func:`registry` and the fake infant (in this process)."""
    import devlearn.env.behavior_env
    import devlearn.plugins

    fake = functools.partial(fake_infant_factory, episode_steps=EPISODE_STEPS)
    reg = registry()
    set_attr = monkeypatch.setattr if monkeypatch else setattr
    set_attr(devlearn.plugins, "PluginRegistry", lambda *a, **k: reg)
    set_attr(devlearn.env.behavior_env, "build_default_infant", fake)


if __name__ == "__main__":
    from devlearn.cli import main

    install()
    sys.exit(main(sys.argv[1:]))
