"""Fixtures the core's tests share."""

from __future__ import annotations

import functools
from collections.abc import Callable

import pytest


@pytest.fixture
def cli_with(monkeypatch) -> Callable[..., Callable[[list[str]], int]]:
    """``cli_with(*behaviors)``: ``devlearn ...`` in process (:func:`devlearn.cli.main`) with
    only ``behaviors`` installed and a fake infant (10-step episodes) in every environment."""

    def install(*behaviors: type) -> Callable[[list[str]], int]:
        import devlearn.plugins
        from devlearn.cli import main
        from devlearn.testing import registry_for
        from devlearn.testing.fake_infant import fake_infant_factory

        registry = registry_for(*behaviors)
        monkeypatch.setattr(devlearn.plugins, "PluginRegistry", lambda *a, **k: registry)
        fake = functools.partial(fake_infant_factory, episode_steps=10)
        monkeypatch.setattr("devlearn.env.behavior_env.build_default_infant", fake)
        return main

    return install


@pytest.fixture
def refused(capsys) -> Callable[..., str]:
    """``refused(cli, *argv)``: ``cli(argv)`` must refuse its input as devlearn does (exit code 2
    and one line on stderr, ``devlearn: error: ...``, no traceback); returns that line."""

    def run(cli: Callable[[list[str]], int], *argv: str) -> str:
        capsys.readouterr()  # drop earlier output (progress bars)
        assert cli(list(argv)) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("devlearn: error: ") and "\n" not in err and "Traceback" not in err
        return err

    return run
