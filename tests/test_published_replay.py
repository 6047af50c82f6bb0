"""Every published policy file still acts as trained: its actions on a fixed observation batch
and one deterministic evaluation episode (every reward, the episode's ``reward/*`` and
``metrics/*``) equal what was recorded before issue #31 (``tests/published_policies.py``), on
this kind of CPU (``tests/cpu_kind.py``: the Intel AVX-512 recordings were made with the code of
913aa79, before issues #38 and #44 changed anything)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from cpu_kind import for_this_cpu, recorded_elsewhere  # noqa: E402
from published_policies import DATA, published_policies, replay, slug  # noqa: E402


@pytest.mark.slow
@pytest.mark.parametrize("path", published_policies(), ids=slug)
def test_published_policy_acts_as_recorded(path):
    reference = DATA / f"{slug(path)}.npz"
    if reason := recorded_elsewhere(reference):
        pytest.skip(reason)
    recorded = np.load(for_this_cpu(reference))  # tests/cpu_kind.py
    now = replay(path)
    assert np.array_equal(now["batch_actions"], recorded["batch_actions"])
    assert np.array_equal(now["first_actions"], recorded["first_actions"])
    assert str(now["actions_sha256"]) == str(recorded["actions_sha256"])
    assert np.array_equal(now["rewards"], recorded["rewards"])
    assert json.loads(str(now["episode_info"])) == json.loads(str(recorded["episode_info"]))
