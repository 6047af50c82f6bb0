"""Fixtures: each scene built once per test module."""

from __future__ import annotations

import numpy as np
import pytest

from devlearn.infant import build_infant


@pytest.fixture(scope="module")
def crib():
    with build_infant("crib") as infant:
        infant.reset(np.random.default_rng(0))
        yield infant


@pytest.fixture(scope="module")
def sitting():
    with build_infant("sitting") as infant:
        infant.reset(np.random.default_rng(0))
        yield infant
