"""The fixed random CNN that encodes images for the forward model."""

from __future__ import annotations

import torch
import torch.nn as nn


class RandomImageFeatures(nn.Module):
    """A fixed random CNN: (B, H, W, C) images, values 0..255 -> (B, features).

    Conv(C->16, k5 s2), Conv(16->32, k3 s2), Conv(32->32, k3 s2), each + ReLU, average-pooled
    to 4x4 (so coarse positions, e.g. where a hand is, survive), then one linear layer. Random
    features are a stable target for a forward model: Burda et al. (2019, "Large-scale study
    of curiosity-driven learning") found them competitive with learned ones.
    """

    def __init__(self, channels: int, features: int) -> None:
        super().__init__()
        self.net = nn.Sequential(
            nn.Conv2d(channels, 16, 5, stride=2, padding=2),
            nn.ReLU(),
            nn.Conv2d(16, 32, 3, stride=2, padding=1),
            nn.ReLU(),
            nn.Conv2d(32, 32, 3, stride=2, padding=1),
            nn.ReLU(),
            nn.AdaptiveAvgPool2d(4),
            nn.Flatten(),
            nn.Linear(32 * 16, features),
        )
        self.requires_grad_(False)

    def forward(self, images: torch.Tensor) -> torch.Tensor:
        """Args: images (B, H, W, C). Returns: (B, features)."""
        return self.net(images.float().permute(0, 3, 1, 2) / 255.0)
