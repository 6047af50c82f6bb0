"""The per-eye CNN of hand regard (paper sec. II-B3)."""

from __future__ import annotations

import torch
import torch.nn as nn

from devlearn import SensorEncoder

EYE_FEATURES = 256
"""Features per eye (paper sec. II-B3)."""


class EyeCNN(nn.Module):
    """(batch, H, W, 3) images, float values in [0, 1] -> (batch, 256) features.

    The network builder hands uint8 images over already divided by 255 (the
    :class:`~devlearn.api.sensors.SensorEncoder` input contract); dividing again here made every
    hand-regard run before the fix learn from near-black images (white became 1/255).

    Conv(3->32, k5 s2 p2), Conv(32->64, k3 s2 p1), Conv(64->128, k3 s2 p1),
    Conv(128->256, k3 s2 p1), each + ReLU, then global average pooling.
    """

    def __init__(self) -> None:
        super().__init__()
        self.convs = nn.Sequential(
            nn.Conv2d(3, 32, kernel_size=5, stride=2, padding=2),
            nn.ReLU(),
            nn.Conv2d(32, 64, kernel_size=3, stride=2, padding=1),
            nn.ReLU(),
            nn.Conv2d(64, 128, kernel_size=3, stride=2, padding=1),
            nn.ReLU(),
            nn.Conv2d(128, EYE_FEATURES, kernel_size=3, stride=2, padding=1),
            nn.ReLU(),
            nn.AdaptiveAvgPool2d(1),
            nn.Flatten(),
        )

    def forward(self, images: torch.Tensor) -> torch.Tensor:
        """Encode images.

        Args:
            images: (batch, H, W, 3) channels-last float in [0, 1].
        Returns:
            (batch, 256) float features.
        """
        return self.convs(images.permute(0, 3, 1, 2))  # to (batch, 3, H, W)


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
        return EyeCNN()

    def out_dim(self, obs_shape: tuple[int, ...]) -> int:
        return EYE_FEATURES
