"""10,000 random-action steps in the crib: no NaN, no MuJoCo warning."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.mark.slow
def test_ten_thousand_random_steps(crib):
    rng = np.random.default_rng(2024)
    for t in range(10_000):
        if t % crib.episode_steps == 0:
            crib.reset(rng, random_pose=True)
        crib.step(rng.uniform(-1.0, 1.0, crib.action_dim))
        if t % 500 == 0:
            crib.touch()
            crib.hand_contacts()
        assert all(w.number == 0 for w in crib.data.warning), f"MuJoCo warning at step {t}"
    data = crib.data
    assert np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.qvel))
    assert np.all(np.isfinite(crib.touch())) and np.all(np.isfinite(crib.proprioception()))
    assert np.abs(data.qvel).max() < 100.0
    crib.reset(np.random.default_rng(0))
