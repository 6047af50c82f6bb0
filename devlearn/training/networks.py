"""Policy and value networks from a behaviour's NetworkSpec, and the tanh/softplus Gaussian."""

from __future__ import annotations

import math

import torch
import torch.nn as nn
import torch.nn.functional as F
from rsl_rl.models import MLPModel
from rsl_rl.modules import EmpiricalNormalization
from rsl_rl.modules.distribution import Distribution
from tensordict import TensorDict
from torch.distributions import Normal

from devlearn.behavior import NetworkSpec


def as_float(x: torch.Tensor) -> torch.Tensor:
    """uint8 observations (images) become floats in [0, 1]; others are cast to float32."""
    return x.float() / 255.0 if x.dtype == torch.uint8 else x.float()


class MultiSenseModel(MLPModel):
    """rsl-rl model: one encoder per observation, concatenated, then fusion + trunk + head.

    ``latent = concat(encoder_k(obs_k))`` over the set's observation groups (any per-sample
    shape, e.g. (2, 64, 64, 3) uint8 images); rsl-rl's ``MLP`` then applies
    ``spec.fusion_dims + spec.trunk_dims`` (Linear + activation each) and one linear head:
    the value for the critic, ``(2, action_dim)`` for the actor's distribution.

    Args:
        obs: A batch of observations (groups of shape (N, *shape)).
        obs_groups: rsl-rl's observation sets, e.g. ``{"actor": [...], "critic": [...]}``.
        obs_set: ``"actor"`` or ``"critic"``.
        output_dim: Action size (actor) or 1 (critic).
        spec: The behaviour's NetworkSpec; its encoders are built afresh for this model.
        activation: Activation of the fusion and trunk layers (paper: ReLU).
        obs_normalization: Not supported (encoders see raw observations); must be False.
        distribution_cfg: rsl-rl distribution config (actor only).
    """

    def __init__(
        self,
        obs: TensorDict,
        obs_groups: dict[str, list[str]],
        obs_set: str,
        output_dim: int,
        spec: NetworkSpec,
        activation: str = "relu",
        obs_normalization: bool = False,
        distribution_cfg: dict | None = None,
    ) -> None:
        if obs_normalization:
            raise ValueError("MultiSenseModel does not normalise observations; encoders do")
        hidden = tuple(spec.fusion_dims) + tuple(spec.trunk_dims)
        if not hidden:
            raise ValueError("NetworkSpec needs at least one fusion or trunk layer")
        self.spec = spec  # plain attribute, read by _get_latent_dim during super().__init__
        super().__init__(
            obs, obs_groups, obs_set, output_dim, hidden, activation, False, distribution_cfg
        )

    def _get_obs_dim(
        self, obs: TensorDict, obs_groups: dict[str, list[str]], obs_set: str
    ) -> tuple[list[str], int]:
        groups = list(obs_groups[obs_set])
        missing = [g for g in groups if g not in self.spec.encoders]
        if missing:
            raise ValueError(
                f"observations {missing} of set '{obs_set}' have no encoder in the NetworkSpec; "
                f"encoders: {sorted(self.spec.encoders)}"
            )
        self.obs_shapes = {g: tuple(int(d) for d in obs[g].shape[1:]) for g in groups}
        return groups, sum(math.prod(s) for s in self.obs_shapes.values())

    def _get_latent_dim(self) -> int:
        self.encoders = nn.ModuleDict(
            {g: self.spec.encoders[g].build(shape) for g, shape in self.obs_shapes.items()}
        )
        unknown = set(self.spec.normalize) - set(self.spec.encoders)
        if unknown:
            raise ValueError(f"NetworkSpec.normalize names unknown observations {sorted(unknown)}")
        self.normalizers = nn.ModuleDict(
            {
                g: EmpiricalNormalization(shape)
                for g, shape in self.obs_shapes.items()
                if g in self.spec.normalize
            }
        )
        return sum(self.spec.encoders[g].out_dim(s) for g, s in self.obs_shapes.items())

    def _input(self, obs: TensorDict, group: str) -> torch.Tensor:
        x = as_float(obs[group])
        return self.normalizers[group](x) if group in self.normalizers else x

    def get_latent(self, obs: TensorDict, masks=None, hidden_state=None) -> torch.Tensor:
        """Normalise the groups named in ``spec.normalize``, encode every group, concatenate.

        Returns:
            (N, latent_dim).
        """
        return torch.cat([self.encoders[g](self._input(obs, g)) for g in self.obs_groups], dim=-1)

    def update_normalization(self, obs: TensorDict) -> None:
        """Update the running statistics of the normalised groups from a rollout batch."""
        for group, normalizer in self.normalizers.items():
            normalizer.update(as_float(obs[group]))  # type: ignore[operator]

    def as_jit(self) -> nn.Module:
        raise NotImplementedError("MultiSenseModel has no TorchScript export; use the checkpoint")

    def as_onnx(self, verbose: bool) -> nn.Module:
        raise NotImplementedError("MultiSenseModel has no ONNX export; use the checkpoint")


def inverse_softplus(y: float) -> float:
    """x such that softplus(x) = y (y > 0)."""
    return y + math.log(-math.expm1(-y))


class TanhSoftplusGaussian(Distribution):
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
    """

    def __init__(
        self,
        output_dim: int,
        init_std: float = 0.5,
        min_std: float = 1e-3,
        max_std: float = 0.0,
    ) -> None:
        super().__init__(output_dim)
        if init_std <= min_std:
            raise ValueError(f"init_std must exceed min_std={min_std}, got {init_std}")
        if max_std and max_std <= init_std:  # 0 means unbounded
            raise ValueError(f"max_std must exceed init_std={init_std} (or be 0), got {max_std}")
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
        self._distribution = Normal(torch.tanh(raw_mean), std)

    def sample(self) -> torch.Tensor:
        return self._distribution.sample()  # type: ignore[union-attr]

    def deterministic_output(self, mlp_output: torch.Tensor) -> torch.Tensor:
        return torch.tanh(mlp_output[..., 0, :])

    def as_deterministic_output_module(self) -> nn.Module:
        return _TanhFirstSlice()

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

    def kl_divergence(self, old_params, new_params) -> torch.Tensor:
        old = Normal(*old_params)
        new = Normal(*new_params)
        return torch.distributions.kl_divergence(old, new).sum(dim=-1)

    def init_mlp_weights(self, mlp: nn.Module) -> None:
        """Start near mean 0 and std ``init_std``: small head weights, matching std bias."""
        head = mlp[-2]  # the last Linear (followed by Unflatten to (2, output_dim))
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
