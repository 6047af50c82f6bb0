"""Reward normalisation: rewards divided by a running spread of the discounted return.

The definition is gymnasium's ``NormalizeReward`` and SB3's ``VecNormalize``: each env keeps its
discounted return ``G_t = gamma * G_{t-1} * (1 - done_{t-1}) + r_t``; a running variance of all
the ``G_t`` seen (over envs and steps, merged across torchrun ranks) scales the reward,
``r_t / sqrt(var + eps)``, clipped to ``[-clip, clip]``. Only the scale changes, so the optimal
policy does not; what changes is that the value targets and advantages have a unit scale
whatever the behaviour's reward scale (self-touch's value loss ran from 5 to 440 without it,
issue #28). The running moments are rsl-rl's own :class:`EmpiricalNormalization` (which merges
ranks with all-reduce); the per-env returns and the moments are saved in checkpoints.
"""

from __future__ import annotations

import torch
import torch.nn as nn
from rsl_rl.modules import EmpiricalNormalization


class RewardNormalizer(nn.Module):
    """Scale rewards by the running standard deviation of each env's discounted return.

    Args:
        num_envs: Environments on this rank.
        gamma: The discount of the returns (PPO's gamma).
        clip: Bound on the normalised reward.
        eps: Added to the variance before the square root.
    """

    returns: torch.Tensor  # buffer (state_dict): (num_envs, 1) discounted returns

    def __init__(self, num_envs: int, gamma: float, clip: float = 10.0, eps: float = 1e-8) -> None:
        super().__init__()
        self.gamma, self.clip, self.eps = float(gamma), float(clip), float(eps)
        self.moments = EmpiricalNormalization(1, eps=0.0)
        self.register_buffer("returns", torch.zeros(num_envs, 1))

    @property
    def std(self) -> float:
        """The current scale: sqrt(running variance of the returns + eps)."""
        return float(torch.sqrt(self.moments._var.squeeze() + self.eps))

    @torch.no_grad()
    def forward(self, rewards: torch.Tensor, dones: torch.Tensor) -> torch.Tensor:
        """Update the returns and moments with one step, then return the scaled rewards.

        Args:
            rewards: (num_envs,) this step's rewards.
            dones: (num_envs,) episodes that ended with this step (their return restarts at
                the next step).
        Returns:
            (num_envs,) ``clip(rewards / std)``, float32.
        """
        self.returns.mul_(self.gamma).add_(rewards.view(-1, 1).to(self.returns.dtype))
        self.moments.update(self.returns)
        scaled = rewards / self.std
        self.returns[dones.view(-1).bool()] = 0.0
        return scaled.clamp(-self.clip, self.clip)
