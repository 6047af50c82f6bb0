"""Runs for tests: a behaviour's run config resolved as ``devlearn run`` resolves it, and the
few entry points into the training and evaluation floors a plugin's tests need (train a tiny
run, open its checkpoint, rebuild its policy, evaluate it), so that those tests import only
``devlearn``, ``devlearn.api`` and ``devlearn.testing``.

Each is a thin door onto the core's one way of doing the thing (``resolve_config``,
``train``, ``Checkpoint``, ``evaluate``): when the core changes, this module changes, not
every plugin's tests. Heavy modules (torch, MuJoCo) load when a function is called.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from devlearn.api.behavior import Behavior
    from devlearn.config.run_config import RunConfig
    from devlearn.plugins import PluginRegistry


def run_config(
    behavior: type[Behavior],
    overrides: Sequence[str] = (),
    preset: str | None = "",
    *,
    registry: PluginRegistry | None = None,
    **top: Any,
) -> RunConfig:
    """The config ``devlearn run NAME --preset PRESET --set OVERRIDES`` (plus top-level
    options ``top``: ``total_steps``, ``num_envs``, ``workers``, ``seed``, ``out_dir``...)
    would train ``behavior`` with: resolved and checked exactly as the run's
    (:func:`devlearn.config.resolve.resolve_config`).

    Args:
        behavior: The behaviour class.
        overrides: ``--set`` items, e.g. ``["behavior.max_std=0.5"]``.
        preset: One of the behaviour's ``presets()``; empty: none.
        registry: Where the behaviour is registered (default: a registry of ``behavior``
            alone, :func:`~devlearn.testing.fixtures.registry_for`).
        top: Top-level fields of the run config; None values are skipped.
    Raises:
        UsageError: What ``devlearn run`` refuses, in its words.
    """
    from devlearn.config.resolve import RunRequest, resolve_config
    from devlearn.testing.fixtures import registry_for

    out_dir = str(top.pop("out_dir", "") or "")
    request = RunRequest(behavior.name, list(overrides), preset or "", top, out_dir=out_dir)
    return resolve_config(request, registry or registry_for(behavior))
