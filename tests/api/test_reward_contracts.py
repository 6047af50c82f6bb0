"""Reward terms: both forms share their name, weight and registration, and only the terms
below the two contracts are classes a config may name."""

from __future__ import annotations

import numpy as np
import pytest

from devlearn.api.errors import UsageError
from devlearn.api.rewards import (
    BatchContext,
    BatchedIntrinsicReward,
    IntrinsicReward,
    RewardTermCfg,
    StepContext,
    registered_terms,
    term_path,
)


class _Once(IntrinsicReward):  # "_": kept out of the listed terms other tests may print
    def __call__(self, ctx: StepContext) -> float:
        return 1.0


class _Batch(BatchedIntrinsicReward):
    def __call__(self, batch: BatchContext) -> np.ndarray:
        return np.ones(len(batch), np.float32)


def test_a_term_of_either_form_is_named_by_its_config():
    for cls in (_Once, _Batch):
        term = RewardTermCfg(cls=cls, weight=2).build("mine")
        assert type(term) is cls and term.weight == 2.0 and term.name == "mine"
    assert _Batch(0.5).num_envs == 0 and _Once().name == "reward"


def test_the_two_contracts_are_not_terms_a_config_may_name():
    for contract in (IntrinsicReward, BatchedIntrinsicReward):
        assert term_path(contract) not in registered_terms()
        with pytest.raises(UsageError, match="unknown reward term class"):
            RewardTermCfg(cls=term_path(contract)).term_class()
