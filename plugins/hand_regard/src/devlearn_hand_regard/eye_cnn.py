"""The per-eye CNN of hand regard (paper sec. II-B3), as a torch module (loaded when a network is
built: :class:`~devlearn_hand_regard.encoders.EyeCNNEncoder`)."""

from __future__ import annotations

import torch
import torch.nn as nn


class EyeCNN(nn.Module):
    """(batch, H, W, 3) images, float values in [0, 1] -> (batch, ``features``) features
    (:data:`~devlearn_hand_regard.encoders.EYE_FEATURES`, the paper's 256).

    The network builder hands uint8 images over already divided by 255 (the
    :class:`~devlearn.api.sensors.SensorEncoder` input contract); dividing again here made every
    hand-regard run before the fix learn from near-black images (white became 1/255).

    Conv(3->32, k5 s2 p2), Conv(32->64, k3 s2 p1), Conv(64->128, k3 s2 p1),
    Conv(128->features, k3 s2 p1), each + ReLU, then global average pooling.

    The ReLUs work in place (each overwrites its convolution's fresh output, which nothing
    else reads): the same outputs and gradients, bit for bit, without allocating and filling
    a second activation per layer (about 4% of a training update's time on one CPU thread,
    measured in docs/benchmarks.md).
    """

    def __init__(self, features: int) -> None:
        super().__init__()
        self.convs = nn.Sequential(
            nn.Conv2d(3, 32, kernel_size=5, stride=2, padding=2),
            nn.ReLU(inplace=True),
            nn.Conv2d(32, 64, kernel_size=3, stride=2, padding=1),
            nn.ReLU(inplace=True),
            nn.Conv2d(64, 128, kernel_size=3, stride=2, padding=1),
            nn.ReLU(inplace=True),
            nn.Conv2d(128, features, kernel_size=3, stride=2, padding=1),
            nn.ReLU(inplace=True),
            nn.AdaptiveAvgPool2d(1),
            nn.Flatten(),
        )

    def forward(self, images: torch.Tensor) -> torch.Tensor:
        """Encode images.

        Args:
            images: (batch, H, W, 3) channels-last float in [0, 1].
        Returns:
            (batch, features) float features.
        """
        return self.convs(images.permute(0, 3, 1, 2))  # to (batch, 3, H, W)
