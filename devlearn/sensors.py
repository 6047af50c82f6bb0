"""The SensorEncoder interface: turns one observation into features for the policy network."""

from __future__ import annotations

from abc import ABC, abstractmethod

import torch.nn as nn


class SensorEncoder(ABC):
    """A factory for the torch module that encodes one observation group.

    A behaviour maps each observation name to an encoder. The network builder
    (:mod:`devlearn.training.networks`) calls :meth:`build` with the observation's per-sample
    shape, then concatenates the encoders' outputs and applies the behaviour's fusion and
    trunk layers (see :class:`devlearn.behavior.NetworkSpec`).
    """

    @abstractmethod
    def build(self, obs_shape: tuple[int, ...]) -> nn.Module:
        """Return a module mapping (batch, *obs_shape) float tensors to (batch, out_dim)."""

    @abstractmethod
    def out_dim(self, obs_shape: tuple[int, ...]) -> int:
        """Return the feature size the built module produces for ``obs_shape``."""


class MLPEncoder(SensorEncoder):
    """A flat observation through Linear+ReLU layers.

    Args:
        hidden_dims: Layer sizes, e.g. ``(128, 256)`` for the paper's 68 -> 128 -> 256 touch MLP.
    """

    def __init__(self, hidden_dims: tuple[int, ...] = (256,)) -> None:
        if not hidden_dims:
            raise ValueError("MLPEncoder needs at least one layer size")
        self.hidden_dims = tuple(int(d) for d in hidden_dims)

    def build(self, obs_shape: tuple[int, ...]) -> nn.Module:
        layers: list[nn.Module] = [nn.Flatten()]
        in_dim = 1
        for d in obs_shape:
            in_dim *= int(d)
        for d in self.hidden_dims:
            layers += [nn.Linear(in_dim, d), nn.ReLU()]
            in_dim = d
        return nn.Sequential(*layers)

    def out_dim(self, obs_shape: tuple[int, ...]) -> int:
        return self.hidden_dims[-1]
