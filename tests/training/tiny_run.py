"""Helpers for training tests: a registry with the tiny behaviour and a config factory.

Run as a script (``python tiny_run.py OUT_DIR TOTAL_STEPS [KEY=VALUE...]``) it trains the tiny
behaviour in process, so tests can kill it at any moment; ``python tiny_run.py --resume
OUT_DIR`` continues such a run.
"""

from __future__ import annotations

import functools
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "env"))

from tiny_behaviors import OtherBehavior  # noqa: E402

from devlearn.testing import registry_for  # noqa: E402
from devlearn.testing.fake_infant import TinyBehavior, fake_infant_factory  # noqa: E402

EPISODE_STEPS = 10
factory = functools.partial(fake_infant_factory, episode_steps=EPISODE_STEPS)


def registry():
    """A registry holding ``tiny`` and ``other``."""
    return registry_for(TinyBehavior, OtherBehavior)


def config(out_dir, total_steps: int = 256, *overrides: str, **top):
    """The tiny behaviour's config: 4 envs x 8 steps per iteration (32 env steps)."""
    from devlearn.testing import run_config

    top = {"num_envs": 4, "workers": 0, "save_interval": 1, **top}
    return run_config(
        TinyBehavior, list(overrides), out_dir=str(out_dir), total_steps=total_steps, **top
    )


if __name__ == "__main__":
    from devlearn.training import train

    if sys.argv[1] == "--resume":
        train(None, registry(), resume=sys.argv[2], infant_factory=factory, progress=False)
    else:
        out, steps, *rest = sys.argv[1:]
        train(config(out, int(steps), *rest), registry(), infant_factory=factory, progress=False)
