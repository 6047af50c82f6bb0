"""Today's code returns, bit for bit, the rollout recorded before the batched facts and
observations (``data/rollout_f17ca1c.npz``, see :mod:`recorded_rollout`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from recorded_rollout import log1p_probe, record_rollout

RECORDED = Path(__file__).parent / "data" / "rollout_f17ca1c.npz"


def test_rollout_matches_the_one_recorded_on_the_previous_code():
    before = np.load(RECORDED)
    now = record_rollout()
    assert now.keys() == set(before.files)
    assert (before["rewards"] != 0).sum() > 40 and before["dones"].sum() == 6  # it has touches
    for key in ("proprioception", "rewards", "dones"):
        assert now[key].shape == before[key].shape, key
        assert now[key].tobytes() == before[key].tobytes(), key
    # every episode value recorded then is the same now; metrics added since (the per-episode
    # balance) are extra keys, left out of the comparison
    keys, old_keys = list(now["episode_keys"]), list(before["episode_keys"])
    assert set(old_keys) <= set(keys)
    values = now["episode_info"].reshape(-1, len(keys))
    kept = values[:, [keys.index(k) for k in old_keys]]
    assert kept.tobytes() == before["episode_info"].tobytes()
    if log1p_probe().tobytes() == before["log1p_probe"].tobytes():
        assert now["body_map"].tobytes() == before["body_map"].tobytes()
    else:  # this machine's numpy rounds log1p differently from the recording machine's
        np.testing.assert_array_max_ulp(now["body_map"], before["body_map"], maxulp=1)
