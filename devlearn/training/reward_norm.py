"""Reward normalisation: rewards divided by a running spread of the discounted return.

The definition is gymnasium's ``NormalizeReward`` and SB3's ``VecNormalize``: each env keeps its
discounted return ``G_t = gamma * G_{t-1} * (1 - done_{t-1}) + r_t``; a running variance of all
the ``G_t`` seen (over envs and steps, merged across torchrun ranks) scales the reward,
``r_t / sqrt(var + eps)``, clipped to ``[-clip, clip]``. Only the scale changes, so the optimal
policy does not; what changes is that the value targets and advantages have a unit scale
whatever the behaviour's reward scale (self-touch's value loss ran from 5 to 440 without it,
issue #28). The running moments (:class:`RunningMoments`) are computed as rsl-rl's
``EmpiricalNormalization`` computes them (merging ranks with all-reduce) and kept in its state
layout; the per-env returns and the moments are saved in checkpoints.
"""

from __future__ import annotations

import torch
import torch.nn as nn


class RunningMoments(nn.Module):
    """The running mean and variance of every row seen so far (one value per row), merged
    batch by batch (Chan et al.'s pairwise update) and across torchrun ranks (all-reduce).

    The arithmetic and the state (``_mean``, ``_var``, ``_std``, ``count``, each (1, 1) but
    the count) are those of rsl-rl's ``EmpiricalNormalization(1)``, which held the moments
    before issue #59: checkpoints saved then load and resume bit for bit; the variance is read
    here through :attr:`var`, not through rsl-rl's private attributes.
    """

    _mean: torch.Tensor
    _var: torch.Tensor
    _std: torch.Tensor
    count: torch.Tensor

    def __init__(self) -> None:
        super().__init__()
        self.register_buffer("_mean", torch.zeros(1, 1))
        self.register_buffer("_var", torch.ones(1, 1))
        self.register_buffer("_std", torch.ones(1, 1))  # kept for the state layout only
        self.register_buffer("count", torch.tensor(0, dtype=torch.long))

    @property
    def var(self) -> torch.Tensor:
        """The running (population) variance, a scalar tensor (1 before any row)."""
        return self._var.squeeze()

    @torch.no_grad()
    def update(self, x: torch.Tensor) -> None:
        """Merge the rows of ``x`` ((rows, 1), this rank's) into the moments.

        With n rows seen before and m now (all ranks), mean ``mu_x`` and variance ``v_x`` of
        the new rows, ``rate = m / (n + m)`` and ``d = mu_x - mu``: ``mu += rate * d``,
        ``var += rate * (v_x - var + d * (mu_x - mu_new))``. A module in eval mode learns
        nothing, as rsl-rl's.
        """
        if not self.training:
            return
        count_x = torch.tensor(x.shape[0], dtype=self.count.dtype, device=self.count.device)
        var_x = torch.var(x, dim=0, unbiased=False, keepdim=True)
        mean_x = torch.mean(x, dim=0, keepdim=True)
        if torch.distributed.is_initialized():
            # the global mean first, then the ranks' variances combined around it
            local_mean_x = mean_x
            torch.distributed.all_reduce(count_x)
            mean_sum_x = mean_x * x.shape[0]
            torch.distributed.all_reduce(mean_sum_x)
            mean_x = mean_sum_x / count_x
            var_sum_x = x.shape[0] * (var_x + (local_mean_x - mean_x).square())
            torch.distributed.all_reduce(var_sum_x)
            var_x = var_sum_x / count_x
        # in place, the same operations as ``self.count += count_x`` etc. (bit for bit), without
        # nn.Module's attribute hooks or a new _std tensor on every call (once per decision)
        self.count.add_(count_x)
        rate = count_x / self.count
        delta_mean = mean_x - self._mean
        self._mean.add_(rate * delta_mean)
        self._var.add_(rate * (var_x - self._var + delta_mean * (mean_x - self._mean)))
        torch.sqrt(self._var, out=self._std)


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
        self.moments = RunningMoments()
        self.register_buffer("returns", torch.zeros(num_envs, 1))

    @property
    def std(self) -> float:
        """The current scale: sqrt(running variance of the returns + eps)."""
        return float(torch.sqrt(self.moments.var + self.eps))

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
        returns = self.returns
        returns.mul_(self.gamma).add_(rewards.view(-1, 1).to(returns.dtype))
        self.moments.update(returns)
        scaled = rewards / self.std
        returns.masked_fill_(dones.view(-1, 1).bool(), 0.0)  # returns[dones] = 0, in place
        return scaled.clamp_(-self.clip, self.clip)
