"""Shared fixtures: a detector calibrated on synthetic babbling (no rendering)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

from devlearn_hand_regard.calibration import calibrate  # noqa: E402
from synthetic import synthetic_babbling  # noqa: E402


@pytest.fixture(scope="session")
def synthetic_params():
    """DetectorParams calibrated on a 1,500-step synthetic babbling recording."""
    return calibrate(synthetic_babbling(1500, seed=0))


@pytest.fixture()
def detector_file(tmp_path, synthetic_params):
    """Path of the synthetic calibration saved as JSON."""
    return synthetic_params.save(tmp_path / "hand_detector.json")
