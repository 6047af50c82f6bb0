"""Reward terms: both forms share their name, weight and registration, and only the concrete,
public terms below the two contracts are classes a config may name."""

from __future__ import annotations

import numpy as np
import pytest

from devlearn.api.errors import UsageError
from devlearn.api.rewards import (
    BatchContext,
    BatchedFromPerEnv,
    BatchedIntrinsicReward,
    IntrinsicReward,
    RewardTermCfg,
    StepContext,
    registered_terms,
    term_path,
)


class Once(IntrinsicReward):
    def __call__(self, ctx: StepContext) -> float:
        return 1.0


class Batch(BatchedIntrinsicReward):
    def __call__(self, batch: BatchContext) -> np.ndarray:
        return np.ones(len(batch), np.float32)


class _Private(Once):
    """A helper a plugin keeps to itself (self_touch's ``_LifetimeNovelty``)."""


class Abstract(BatchedIntrinsicReward):
    """A base that leaves ``__call__`` to its subclasses."""


def test_a_term_of_either_form_is_named_by_its_config():
    for cls in (Once, Batch):
        term = RewardTermCfg(cls=cls, weight=2).build("mine")
        assert type(term) is cls and term.weight == 2.0 and term.name == "mine"
    assert Batch(0.5).num_envs == 0 and Once().name == "reward"


def test_the_two_contracts_are_not_terms_a_config_may_name():
    for contract in (IntrinsicReward, BatchedIntrinsicReward):
        assert term_path(contract) not in registered_terms()
        with pytest.raises(UsageError, match="unknown reward term class"):
            RewardTermCfg(cls=term_path(contract)).term_class()


def test_private_abstract_and_adapter_classes_are_not_terms_a_config_may_name():
    # registered as Python defined them, but none is a term a config may build: each was
    # built and crashed with a TypeError traceback (issue #55, fault 3)
    for cls in (_Private, Abstract, BatchedFromPerEnv):
        assert term_path(cls) not in registered_terms()
        with pytest.raises(UsageError, match=r"unknown reward term class .*; valid: .*:Once"):
            RewardTermCfg(cls=term_path(cls)).build("mine")
