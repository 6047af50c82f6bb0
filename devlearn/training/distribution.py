"""The policy's action distributions: the paper's tanh-mean, softplus-spread Gaussian (sec.
II-A4), the bounded Gaussian, the free Gaussian of SB3 and cleanrl, and the tanh-squashed Gaussian
(issue #54)."""

from __future__ import annotations

import math
from typing import cast

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F
from rsl_rl.modules.distribution import Distribution
from torch.distributions import Normal

from devlearn.api.network_spec import check_spread
from devlearn.env.motor_noise import check_noise, power_law_filters


def inverse_softplus(y: float) -> float:
    """x such that softplus(x) = y (y > 0)."""
    return y + math.log(-math.expm1(-y))


def spread_cap(start: float, final: float, progress: float) -> float:
    """The ceiling on the policy's spread at ``progress`` (0 to 1) through the run: falling
    log-linearly from ``start`` (the head's initial spread) to ``final`` (issue #54: a policy
    that explores widely at first and whose mean action is its behaviour at the end)."""
    progress = min(max(progress, 0.0), 1.0)
    return math.exp(math.log(start) + (math.log(final) - math.log(start)) * progress)


class DiagonalNormal(Distribution):
    """What every policy head shares: a diagonal Normal set by :meth:`update`, sampled, scored
    and compared dimension by dimension (summed over actions).

    With ``final_std`` set (:meth:`set_progress`), the spread is capped by a ceiling that falls
    from the initial spread to ``final_std`` over the run (:func:`spread_cap`); the cap is a
    function of the run's progress, not a learned parameter, so it is not saved with the
    weights and a checkpoint's cap follows from its steps and config.
    """

    _distribution: Normal | None = None
    final_std: float = 0.0
    """The spread's ceiling at the end of the run; 0: no ceiling."""
    std_cap: float = math.inf
    """The ceiling now (:meth:`set_progress`)."""

    def set_final_std(self, final_std: float, floor: float, init_std: float) -> None:
        """Check and keep ``final_std`` (0: none): it must lie in [``floor``, ``init_std``).

        Raises:
            ValueError: ``final_std`` outside that range.
        """
        if final_std and not floor <= final_std < init_std:
            raise ValueError(
                f"final_std must lie in [{floor}, {init_std}) (the spread's floor and its "
                f"initial value), got {final_std}"
            )
        self.final_std = float(final_std)

    def set_progress(self, progress: float) -> None:
        """Set the spread's ceiling for ``progress`` (0 to 1) through the run (no-op without
        ``final_std``)."""
        if self.final_std > 0:
            self.std_cap = spread_cap(getattr(self, "init_std", 1.0), self.final_std, progress)

    def capped(self, std: torch.Tensor) -> torch.Tensor:
        """``std`` under the ceiling (unchanged without one)."""
        return std.clamp(max=self.std_cap) if math.isfinite(self.std_cap) else std

    noise_beta: float = 0.0
    """The exploration noise's spectral exponent (``network.exploration_beta``): 0, white
    (independent draws at every decision, the default); above 0, :class:`ColoredNoise`."""
    noise_streams: ColoredNoise | None = None
    """The coloured exploration's streams (made on the first draw, for its batch's shape);
    :class:`~devlearn.evaluation.policy.ActorActions` swaps in each slot's own."""

    def set_noise(self, beta: float, decision_s: float) -> None:
        """Sample with time-correlated noise whose power falls as f^-``beta``, one stream per
        environment and action, advanced once per decision of ``decision_s`` seconds (beta 0:
        white, as without this call)."""
        check_noise(1.0, beta, "network.exploration")
        if beta and not decision_s > 0:
            raise ValueError(
                f"coloured exploration needs a decision period above 0 s, got {decision_s}"
            )
        self.noise_beta, self.noise_decision_s = float(beta), float(decision_s)
        self.noise_streams = None

    def sample(self) -> torch.Tensor:
        dist = self._distribution
        assert dist is not None
        if not self.noise_beta:
            return dist.sample()
        return dist.mean + dist.stddev * self.next_noise(tuple(dist.mean.shape))

    def next_noise(self, shape: tuple[int, ...]) -> torch.Tensor:
        """The coloured streams' next unit-variance draw, ``shape`` (a new batch shape, e.g.
        an evaluation's envs, starts its own streams)."""
        if self.noise_streams is None or self.noise_streams.shape != shape:
            self.noise_streams = ColoredNoise(shape, self.noise_beta, self.noise_decision_s)
        return self.noise_streams.next()

    @property
    def mean(self) -> torch.Tensor:
        return self._distribution.mean  # type: ignore[union-attr]

    @property
    def std(self) -> torch.Tensor:
        return self._distribution.stddev  # type: ignore[union-attr]

    @property
    def entropy(self) -> torch.Tensor:
        return self._distribution.entropy().sum(dim=-1)  # type: ignore[union-attr]

    @property
    def params(self) -> tuple[torch.Tensor, ...]:
        return (self.mean, self.std)

    def log_prob(self, outputs: torch.Tensor) -> torch.Tensor:
        return self._distribution.log_prob(outputs).sum(dim=-1)  # type: ignore[union-attr]

    def kl_divergence(
        self,
        old_params: tuple[torch.Tensor, torch.Tensor],
        new_params: tuple[torch.Tensor, torch.Tensor],
    ) -> torch.Tensor:
        return torch.distributions.kl_divergence(Normal(*old_params), Normal(*new_params)).sum(-1)


class ColoredNoise:
    """Unit-variance Gaussian noise with a power spectrum ~ f^-beta, one stream per element of
    ``shape`` (environments x actions), for the policy's exploration (issue #54).

    Each stream is the motor noise's sum of AR(1) processes
    (:func:`devlearn.env.motor_noise.power_law_filters`), advanced once per decision. Every
    draw is still N(0, 1) per element, so an action mean + std * noise has the policy's
    Gaussian as its law at each decision and PPO's log-probabilities hold; only successive
    draws are correlated. Exploration then drifts smoothly, as a slightly perturbed
    deterministic policy acts, instead of jittering at every decision (pink noise: Eberhard
    et al., ICLR 2023; gSDE's motivation: Raffin et al., CoRL 2021). Draws come from torch's
    generator (a run's seed); the streams are not saved in checkpoints, so a resumed run
    starts fresh ones.

    Args:
        shape: The streams' shape (the batch of means).
        beta: Spectral exponent, 0 <= beta < 2.
        decision_s: Seconds between draws (the physics step times ``env.action_repeat``).
    """

    def __init__(self, shape: tuple[int, ...], beta: float, decision_s: float) -> None:
        a, variance = power_law_filters(float(beta), float(decision_s))
        self.shape = tuple(shape)
        view = (-1,) + (1,) * len(self.shape)
        self._a = torch.tensor(a, dtype=torch.float32).view(view)
        self._gain = torch.tensor(np.sqrt(variance * (1.0 - a**2)), dtype=torch.float32).view(view)
        spread = torch.tensor(np.sqrt(variance), dtype=torch.float32).view(view)
        self.state = torch.randn((len(a), *self.shape)) * spread
        """(K, *shape): each AR(1) process's value, started from its stationary law."""

    def next(self) -> torch.Tensor:
        """The next draw, ``shape``."""
        self.state = self.state * self._a + self._gain * torch.randn_like(self.state)
        return self.state.sum(dim=0)


class TanhSoftplusGaussian(DiagonalNormal):
    """Diagonal Gaussian with ``mean = tanh(W_mu h + b_mu)`` and ``std = softplus(W_s h + b_s)``.

    Both heads read the trunk features, so the spread is state-dependent (paper, sec. II-A4,
    eq. for mu_t and sigma_t). ``min_std`` is added to the softplus so the log-probability
    stays finite when the softplus underflows; samples are not squashed (the env clips them
    to [-1, 1]) and the deterministic action is the mean.

    With ``max_std`` set, the spread is bounded instead: ``std = min_std + (max_std - min_std) *
    sigmoid(W_s h + b_s)``. Because actions are clipped, an unbounded std meets no resistance
    from the clipped returns and grows under the entropy bonus until every action is +-1 noise
    (our 8M self_touch run ended near std 1000, see ``results/self_touch/README.md``).

    Args:
        output_dim: Action size.
        init_std: Standard deviation at initialisation (sets the softplus bias).
        min_std: Small positive floor added to the standard deviation.
        max_std: Upper bound on the standard deviation; 0: unbounded (the paper).
        final_std: The spread's ceiling at the end of the run (:meth:`set_progress`); 0: none.
    """

    def __init__(
        self,
        output_dim: int,
        init_std: float = 0.5,
        min_std: float = 1e-3,
        max_std: float = 0.0,
        final_std: float = 0.0,
        noise_beta: float = 0.0,
        noise_decision_s: float = 0.0,
    ) -> None:
        super().__init__(output_dim)
        self.set_noise(noise_beta, noise_decision_s)
        check_spread(init_std, max_std, min_std)
        self.set_final_std(final_std, min_std, init_std)
        self.init_std = float(init_std)
        self.min_std = float(min_std)
        self.max_std = float(max_std)
        self._distribution: Normal | None = None
        Normal.set_default_validate_args(False)

    @property
    def input_dim(self) -> list[int]:
        """The MLP outputs (..., 2, output_dim): raw mean, then raw std."""
        return [2, self.output_dim]

    def update(self, mlp_output: torch.Tensor) -> None:
        raw_mean, raw_std = torch.unbind(mlp_output, dim=-2)
        if not self.max_std:
            std = F.softplus(raw_std) + self.min_std
        else:
            std = self.min_std + (self.max_std - self.min_std) * torch.sigmoid(raw_std)
        self._distribution = Normal(torch.tanh(raw_mean), self.capped(std))

    def deterministic_output(self, mlp_output: torch.Tensor) -> torch.Tensor:
        return torch.tanh(mlp_output[..., 0, :])

    def as_deterministic_output_module(self) -> nn.Module:
        return _TanhFirstSlice()

    def init_mlp_weights(self, mlp: nn.Sequential) -> None:
        """Start near mean 0 and std ``init_std``: small head weights, matching std bias."""
        head = cast(
            nn.Linear, mlp[-2]
        )  # the last Linear (followed by Unflatten to (2, output_dim))
        with torch.no_grad():
            head.weight.mul_(0.01)
            head.bias[: self.output_dim].zero_()
            if not self.max_std:
                bias = inverse_softplus(self.init_std - self.min_std)
            else:
                frac = (self.init_std - self.min_std) / (self.max_std - self.min_std)
                bias = math.log(frac / (1.0 - frac))  # inverse sigmoid
            head.bias[self.output_dim :].fill_(bias)


class _TanhFirstSlice(nn.Module):
    """Export-friendly deterministic output: tanh of the raw mean."""

    def forward(self, mlp_output: torch.Tensor) -> torch.Tensor:
        return torch.tanh(mlp_output[..., 0, :])


class LinearMeanGaussian(DiagonalNormal):
    """What the state-independent heads share: the MLP outputs the mean alone (a plain linear
    layer), one spread per action from :meth:`current_std` (under the ceiling, if any), the
    deterministic action the mean clipped to [-1, 1] as the env applies it, and a small mean
    layer at the start. Subclasses say how the spread is parameterised."""

    def current_std(self) -> torch.Tensor:
        """(output_dim,) spread."""
        raise NotImplementedError

    @property
    def input_dim(self) -> int:
        """The MLP outputs the mean only."""
        return self.output_dim

    def update(self, mlp_output: torch.Tensor) -> None:
        std = self.capped(self.current_std())
        self._distribution = Normal(mlp_output, std.expand_as(mlp_output))

    def deterministic_output(self, mlp_output: torch.Tensor) -> torch.Tensor:
        """The mean as the env applies it: clipped to [-1, 1]."""
        return mlp_output.clamp(-1.0, 1.0)

    def as_deterministic_output_module(self) -> nn.Module:
        return nn.Hardtanh()  # clamp to [-1, 1], exportable

    def init_mlp_weights(self, mlp: nn.Sequential) -> None:
        """Start near mean 0: small weights and zero bias on the mean's layer."""
        head = cast(nn.Linear, mlp[-1])
        with torch.no_grad():
            head.weight.mul_(0.01)
            head.bias.zero_()


class BoundedGaussian(LinearMeanGaussian):
    """Diagonal Gaussian with a linear mean and a state-independent, bounded spread.

    ``mean = W_mu h + b_mu`` (no squashing) and, per action dimension,
    ``log std = log min_std + (log max_std - log min_std) * sigmoid(p)`` with ``p`` a learned
    parameter: the spread can neither collapse below ``min_std`` nor run away past ``max_std``
    under an entropy bonus, and near a bound its gradient fades smoothly instead of being cut
    by a clamp (which pins a parameter at the bound for good). The env clips sampled actions
    to [-1, 1]. Where the best action lies at a bound, samples past it all earn the same clipped
    reward, so the mean stops being pushed once almost no sample falls inside the range: it
    settles a few spreads past the bound (the paper's ``tanh`` mean instead always has half
    its samples inside and its pre-activation grows without limit; issue #28).

    Args:
        output_dim: Action size.
        init_std: Spread at initialisation.
        min_std: Lower bound of the spread.
        max_std: Upper bound of the spread.
    """

    def __init__(
        self,
        output_dim: int,
        init_std: float = 0.5,
        min_std: float = 0.05,
        max_std: float = 1.0,
        final_std: float = 0.0,
        noise_beta: float = 0.0,
        noise_decision_s: float = 0.0,
    ) -> None:
        super().__init__(output_dim)
        self.set_noise(noise_beta, noise_decision_s)
        self.set_final_std(final_std, min_std, init_std)
        if not 0 < min_std < init_std < max_std:
            raise ValueError(
                f"the spread needs 0 < min_std < init_std < max_std; got min_std={min_std}, "
                f"init_std={init_std}, max_std={max_std}"
            )
        self.min_std, self.init_std, self.max_std = float(min_std), float(init_std), float(max_std)
        self._log_min, self._log_span = math.log(min_std), math.log(max_std / min_std)
        frac = (math.log(init_std) - self._log_min) / self._log_span
        self.std_param = nn.Parameter(torch.full((output_dim,), math.log(frac / (1.0 - frac))))
        self._distribution: Normal | None = None
        Normal.set_default_validate_args(False)

    def current_std(self) -> torch.Tensor:
        """(output_dim,) spread."""
        return torch.exp(self._log_min + self._log_span * torch.sigmoid(self.std_param))


class FreeGaussian(LinearMeanGaussian):
    """Diagonal Gaussian with a linear mean and a free state-independent log-spread (SB3's and
    cleanrl's PPO head): ``mean = W_mu h + b_mu``, ``std = exp(p)`` per action with ``p`` a
    learned parameter, no bounds. The env clips samples to [-1, 1]; the deterministic action is
    the mean clipped the same way, so a mean past a bound plays the bound.

    Args:
        output_dim: Action size.
        init_std: Spread at initialisation (SB3: 1.0).
    """

    def __init__(
        self,
        output_dim: int,
        init_std: float = 1.0,
        final_std: float = 0.0,
        noise_beta: float = 0.0,
        noise_decision_s: float = 0.0,
    ) -> None:
        super().__init__(output_dim)
        self.set_noise(noise_beta, noise_decision_s)
        if not init_std > 0:
            raise ValueError(f"init_std must be above 0, got {init_std}")
        self.set_final_std(final_std, 0.0, init_std)
        self.init_std = float(init_std)
        self.log_std = nn.Parameter(torch.full((output_dim,), math.log(init_std)))
        self._distribution: Normal | None = None
        Normal.set_default_validate_args(False)

    def current_std(self) -> torch.Tensor:
        """(output_dim,) spread."""
        return torch.exp(self.log_std)


SQUASH_EDGE = 1.0 - 1e-6
"""Squashed actions are kept inside +-this so that atanh stays finite."""


class SquashedGaussian(FreeGaussian):
    """A Gaussian squashed by ``tanh``: ``u ~ N(W_mu h + b_mu, exp(p))``, action ``a = tanh(u)``
    (SAC's head, used here for PPO). Samples never leave (-1, 1), so the env's clip never acts
    and nothing past a bound is invisible to the gradient; the log-probability carries the
    change of variables, ``log p(a) = log N(atanh a) - sum log(1 - a^2)``, and the entropy is
    estimated from one reparameterised sample (``-log p(a)``), which falls as samples pile up at
    the bounds (a Gaussian entropy would keep rewarding a spread that only saturates). The
    deterministic action is ``tanh`` of the mean. ``params`` are the Gaussian's (mean, std)
    before squashing (the KL of the adaptive schedule is the same before and after).
    """

    def sample(self) -> torch.Tensor:
        # the Gaussian's draw, coloured where network.exploration_beta asks, then squashed
        return torch.tanh(super().sample()).clamp(-SQUASH_EDGE, SQUASH_EDGE)

    @property
    def entropy(self) -> torch.Tensor:
        dist = self._distribution
        assert dist is not None
        squashed = torch.tanh(dist.rsample()).clamp(-SQUASH_EDGE, SQUASH_EDGE)
        return -self.log_prob(squashed)

    def log_prob(self, outputs: torch.Tensor) -> torch.Tensor:
        a = outputs.clamp(-SQUASH_EDGE, SQUASH_EDGE)
        # log|d tanh(u)/du| = log(1 - tanh(u)^2), in a form that is stable near the bounds
        u = torch.atanh(a)
        log_det = 2.0 * (math.log(2.0) - u - F.softplus(-2.0 * u))
        return (self._distribution.log_prob(u) - log_det).sum(dim=-1)  # type: ignore[union-attr]

    def deterministic_output(self, mlp_output: torch.Tensor) -> torch.Tensor:
        return torch.tanh(mlp_output)

    def as_deterministic_output_module(self) -> nn.Module:
        return nn.Tanh()
