"""Fixtures for the self_touch tests."""

from __future__ import annotations

import pytest
from self_touch_fakes import make_regions


@pytest.fixture
def fake_regions():
    """A fake 68-region table (see :func:`self_touch_fakes.make_regions`)."""
    return make_regions()
