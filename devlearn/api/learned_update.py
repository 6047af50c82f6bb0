"""The torch side of a learned reward's update: the running reward scale, the ranks' gradients.

Kept apart from :mod:`devlearn.api.learned`, the contract a plugin imports to register a term, so
that registering one (``devlearn plugins``, ``config``) loads no torch.
"""

from __future__ import annotations

import torch
import torch.nn as nn


class RunningScale(nn.Module):
    """Running variance of a scalar stream (Chan et al.'s parallel update); divides by its std.

    Its buffers are in :meth:`state_dict`, so a resumed run keeps the scale.
    """

    count: torch.Tensor  # buffers (state_dict): () float64 each
    mean: torch.Tensor
    m2: torch.Tensor

    def __init__(self) -> None:
        super().__init__()
        self.register_buffer("count", torch.zeros((), dtype=torch.float64))
        self.register_buffer("mean", torch.zeros((), dtype=torch.float64))
        self.register_buffer("m2", torch.zeros((), dtype=torch.float64))

    def update(self, values: torch.Tensor) -> None:
        """Add a batch of values, (B,). All-reduced over ranks when distributed."""
        stats = torch.stack(
            [
                torch.tensor(float(values.numel()), dtype=torch.float64, device=values.device),
                values.double().sum(),
                values.double().square().sum(),
            ]
        )
        if distributed():
            torch.distributed.all_reduce(stats)
        n, total, squares = stats.tolist()
        if n == 0:
            return
        mean_b = total / n
        m2_b = max(squares - n * mean_b * mean_b, 0.0)
        count = float(self.count)
        delta = mean_b - float(self.mean)
        new_count = count + n
        self.mean.fill_(float(self.mean) + delta * n / new_count)
        self.m2.fill_(float(self.m2) + m2_b + delta * delta * count * n / new_count)
        self.count.fill_(new_count)

    @property
    def std(self) -> float:
        """The running standard deviation (1 before any value)."""
        count = float(self.count)
        return (float(self.m2) / count) ** 0.5 if count > 1 else 1.0

    def forward(self, values: torch.Tensor) -> torch.Tensor:
        """Return ``values / std``, same shape."""
        return values / max(self.std, 1e-8)


def distributed() -> bool:
    """Whether torchrun's process group is up (then scales and gradients span the ranks)."""
    return torch.distributed.is_available() and torch.distributed.is_initialized()


def average_gradients(params: list[torch.Tensor]) -> None:
    """Average gradients over torchrun's ranks (one all-reduce of the flattened gradients)."""
    if not distributed():
        return
    world = torch.distributed.get_world_size()
    if world < 2 or not params:
        return
    grads = [p.grad if p.grad is not None else torch.zeros_like(p) for p in params]
    flat = torch.cat([g.reshape(-1) for g in grads])
    torch.distributed.all_reduce(flat)
    flat /= world
    offset = 0
    for p in params:
        n = p.numel()
        p.grad = flat[offset : offset + n].view_as(p).clone()
        offset += n
