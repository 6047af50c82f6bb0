"""Fixtures: each scene built once per test module."""

from __future__ import annotations

import numpy as np
import pytest

from devlearn.infant import build_infant


@pytest.fixture(scope="module")
def crib():
    infant = build_infant("crib")
    infant.reset(np.random.default_rng(0))
    yield infant
    infant.close()


@pytest.fixture(scope="module")
def sitting():
    infant = build_infant("sitting")
    infant.reset(np.random.default_rng(0))
    yield infant
    infant.close()
