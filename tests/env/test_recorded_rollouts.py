"""Rollouts recorded before issue #31's reward-term pipeline replay bit for bit: every reward,
every term's per-episode sum, every observation (``tests/env/recorded_rollouts.py``)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from recorded_rollouts import DATA, ROLLOUTS, rollout  # noqa: E402


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(ROLLOUTS))
def test_rollout_replays_bit_for_bit(name):
    recorded = np.load(DATA / f"{name}.npz")
    now = rollout(name)
    assert now["term_names"].tolist() == recorded["term_names"].tolist()
    assert now["obs_names"].tolist() == recorded["obs_names"].tolist()
    for key in ("rewards", "term_sums", "dones", "obs_sums"):
        assert np.array_equal(now[key], recorded[key]), f"{name}: {key} differ"
    assert str(now["obs_sha256"]) == str(recorded["obs_sha256"])
    assert json.loads(str(now["episode_infos"])) == json.loads(str(recorded["episode_infos"]))
