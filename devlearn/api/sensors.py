"""The SensorEncoder interface: turns one observation into features for the policy network."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # torch loads when a network is built, not when a plugin registers an encoder
    import torch.nn as nn


class SensorEncoder(ABC):
    """A factory for the torch module that encodes one observation group.

    A behaviour maps each observation name to an encoder. The network builder
    (:mod:`devlearn.training.networks`) calls :meth:`build` with the observation's per-sample
    shape, then concatenates the encoders' outputs and applies the behaviour's fusion and
    trunk layers (see :class:`devlearn.api.network_spec.NetworkSpec`).

    Input contract: the built module receives float32 tensors of shape (batch, *obs_shape).
    Observations that the behaviour returns as uint8 (camera images, 0..255) arrive already
    scaled to [0, 1] (divided by 255 once, by the network builder); float observations arrive
    as they were observed, or standardised when named in ``NetworkSpec.normalize``. A module
    must not rescale its input again.
    """

    @abstractmethod
    def build(self, obs_shape: tuple[int, ...]) -> nn.Module:
        """Return a module mapping (batch, *obs_shape) float32 tensors to (batch, out_dim).

        uint8 observations arrive as float32 in [0, 1] (see the class docstring).
        """

    @abstractmethod
    def out_dim(self, obs_shape: tuple[int, ...]) -> int:
        """Return the feature size the built module produces for ``obs_shape``."""


class MLPEncoder(SensorEncoder):
    """A flat observation through Linear+activation layers.

    Args:
        hidden_dims: Layer sizes, e.g. ``(128, 256)`` for the paper's 68 -> 128 -> 256 touch MLP.
        activation: The layers' activation, by rsl-rl's name (``relu``, ``tanh``, ``elu``...).
    """

    activation: str = "relu"  # what encoders pickled before the argument existed used

    def __init__(self, hidden_dims: tuple[int, ...] = (256,), activation: str = "relu") -> None:
        if not hidden_dims:
            raise ValueError("MLPEncoder needs at least one layer size")
        self.hidden_dims = tuple(int(d) for d in hidden_dims)
        self.activation = activation

    def build(self, obs_shape: tuple[int, ...]) -> nn.Module:
        import torch.nn as nn
        from rsl_rl.utils import resolve_nn_activation

        layers: list[nn.Module] = [nn.Flatten()]
        in_dim = 1
        for d in obs_shape:
            in_dim *= int(d)
        for d in self.hidden_dims:
            layers += [nn.Linear(in_dim, d), resolve_nn_activation(self.activation)]
            in_dim = d
        return nn.Sequential(*layers)

    def out_dim(self, obs_shape: tuple[int, ...]) -> int:
        return self.hidden_dims[-1]


class FlattenEncoder(SensorEncoder):
    """No layers of its own: the observation flattened, straight into the fusion layers (SB3's
    ``MultiInputPolicy`` feeds every vector observation to one MLP this way)."""

    def build(self, obs_shape: tuple[int, ...]) -> nn.Module:
        import torch.nn as nn

        return nn.Flatten()

    def out_dim(self, obs_shape: tuple[int, ...]) -> int:
        size = 1
        for d in obs_shape:
            size *= int(d)
        return size
