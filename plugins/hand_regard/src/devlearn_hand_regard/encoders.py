"""The per-eye CNN of hand regard (paper sec. II-B3) as a :class:`devlearn.SensorEncoder`.

The encoder is a factory: torch loads only when it builds the module
(:mod:`devlearn_hand_regard.eye_cnn`), so the behaviour's ``network()`` (which
``devlearn config`` calls to check a config, as ``devlearn run`` does) loads no torch."""

from __future__ import annotations

from typing import TYPE_CHECKING

from devlearn import SensorEncoder

if TYPE_CHECKING:
    import torch.nn as nn

EYE_FEATURES = 256
"""Features per eye (paper sec. II-B3)."""


class EyeCNNEncoder(SensorEncoder):
    """The paper's per-eye CNN as a :class:`devlearn.SensorEncoder` (one per eye).

    The paper lists four stride-2 convolutions and then "Flatten -> 256-D vector per eye", but
    a 64x64 image leaves a 4x4x256 map, whose flattening is 4,096-D, not 256-D. We keep the
    paper's 256 features per eye (so the concatenation is the paper's 256 + 256 + 64 = 576) by
    global average pooling over the 4x4 map. The pooling also makes the encoder work for any
    eye size.
    """

    def build(self, obs_shape: tuple[int, ...]) -> nn.Module:
        if len(obs_shape) != 3 or obs_shape[-1] != 3:
            raise ValueError(f"EyeCNNEncoder needs (H, W, 3) images, got shape {obs_shape}")
        from devlearn_hand_regard.eye_cnn import EyeCNN

        return EyeCNN(EYE_FEATURES)

    def out_dim(self, obs_shape: tuple[int, ...]) -> int:
        return EYE_FEATURES
