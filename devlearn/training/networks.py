"""Policy and value networks from a behaviour's NetworkSpec (separate or shared layout)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import torch
import torch.nn as nn
from rsl_rl.models import MLPModel
from rsl_rl.modules import EmpiricalNormalization
from rsl_rl.utils import resolve_nn_activation
from tensordict import TensorDict

from devlearn.api.network_spec import NetworkSpec
from devlearn.training.distribution import TanhSoftplusGaussian, inverse_softplus

Observations = TensorDict | Mapping[str, torch.Tensor]
"""A batch of observation groups, each (N, *shape): rsl-rl's TensorDict or a plain dict."""

__all__ = ["MultiSenseModel", "SharedBody", "TanhSoftplusGaussian", "as_float", "inverse_softplus"]


def as_float(x: torch.Tensor, legacy_uint8_scale: bool = False) -> torch.Tensor:
    """uint8 observations (images) become floats in [0, 1]; others are cast to float32.

    ``legacy_uint8_scale`` divides uint8 values by 255 once more, as every hand-regard run
    before the fix did (``EyeCNN`` divided its already-scaled input again), so that those
    checkpoints see the input scale they were trained on.
    """
    if x.dtype != torch.uint8:
        return x.float()
    x = x.float() / 255.0
    return x / 255.0 if legacy_uint8_scale else x


def _trunk(in_dim: int, dims: tuple[int, ...], activation: str) -> nn.Sequential:
    layers: list[nn.Module] = []
    for dim in dims:
        layers += [nn.Linear(in_dim, dim), resolve_nn_activation(activation)]
        in_dim = dim
    return nn.Sequential(*layers)


class SharedBody(nn.Module):
    """Encoders, normalisers, fusion and trunk that the policy and value heads both read.

    ``features = trunk(fusion(concat(encoder_k(normalise(obs_k)))))``, (N, out_dim). The actor
    owns the body; the critic holds a plain reference, so the body's parameters appear once in
    ``actor.parameters()`` and nowhere in ``critic.parameters()`` (rsl-rl's optimiser and its
    per-network gradient clipping then treat each tensor once). The last result is reused when
    the same observation object comes again with unchanged parameters and the same autograd
    mode (see :meth:`forward`), which is how rsl-rl calls actor and critic (``act``: actor,
    critic, critic; ``update``: actor, critic per mini-batch, one backward over both losses):
    the body runs once per batch, not two or three times, and both losses backpropagate
    through the one graph.
    """

    def __init__(
        self,
        spec: NetworkSpec,
        obs_shapes: dict[str, tuple[int, ...]],
        activation: str,
        legacy_uint8_scale: bool = False,
    ) -> None:
        super().__init__()
        hidden = tuple(spec.fusion_dims) + tuple(spec.trunk_dims)
        if not hidden:
            raise ValueError("NetworkSpec needs at least one fusion or trunk layer")
        self.groups = list(obs_shapes)
        self.legacy_uint8_scale = legacy_uint8_scale
        self.encoders = nn.ModuleDict(
            {g: spec.encoders[g].build(shape) for g, shape in obs_shapes.items()}
        )
        self.normalizers = nn.ModuleDict(
            {g: EmpiricalNormalization(s) for g, s in obs_shapes.items() if g in spec.normalize}
        )
        latent = sum(spec.encoders[g].out_dim(s) for g, s in obs_shapes.items())
        self.trunk = _trunk(latent, hidden, activation)
        self.out_dim = hidden[-1]
        self._last: tuple | None = None

    def forward(self, obs: Observations, caller: int = 0) -> torch.Tensor:
        """Features of a batch (``obs[group]`` of shape (N, *shape)); returns (N, out_dim).

        ``caller`` identifies the model asking. Without gradients a result is reused by
        anyone; with gradients only once, by another model (the critic after the actor), so a
        graph that a backward pass may already have freed is never handed out twice.
        """
        grad = torch.is_grad_enabled()
        # in-place updates (optimiser steps, loading, normaliser updates) bump these versions
        versions = (next(self.trunk.parameters())._version,) + tuple(
            n.count._version for n in self.normalizers.values()
        )
        key = (versions, grad, torch.is_inference_mode_enabled())
        last = self._last
        reusable = last is not None and last[0] is obs and last[1] == key
        if last is not None and reusable and not (grad and last[3] == caller):
            if grad:
                self._last = None
            return last[2]
        features = self.encode(obs)
        self._last = (obs, key, features, caller)
        return features

    def encode(self, obs: Observations) -> torch.Tensor:
        """:meth:`forward` without reuse (for export): (N, out_dim) features."""
        parts = []
        for g in self.groups:
            x = as_float(obs[g], self.legacy_uint8_scale)
            if g in self.normalizers:
                x = self.normalizers[g](x)
            parts.append(self.encoders[g](x))
        return self.trunk(torch.cat(parts, dim=-1))

    def update_normalization(self, obs: TensorDict) -> None:
        """Update the running statistics of the normalised groups from a rollout batch."""
        for group, normalizer in self.normalizers.items():
            normalizer.update(as_float(obs[group], self.legacy_uint8_scale))  # type: ignore[operator]


class MultiSenseModel(MLPModel):
    """rsl-rl model: one encoder per observation, concatenated, then fusion + trunk + head.

    ``latent = concat(encoder_k(obs_k))`` over the set's observation groups (any per-sample
    shape, e.g. (2, 64, 64, 3) uint8 images, which arrive as float32 in [0, 1]); then
    ``spec.fusion_dims + spec.trunk_dims`` (Linear + activation each) and one linear head: the
    value for the critic, ``(2, action_dim)`` for the actor's distribution.

    Two layouts. ``shared=False`` (``separate``, every run before the shared layout existed):
    the model holds its own encoders, normalisers and fusion + trunk + head MLP. ``shared=True``
    (the paper's Models I and II): the actor builds a :class:`SharedBody` and exposes it as
    ``cnns``, which rsl-rl's ``share_cnn_encoders`` hands to the critic's constructor; each
    model's ``mlp`` is then only its head.

    Args:
        obs: A batch of observations (groups of shape (N, *shape)).
        obs_groups: rsl-rl's observation sets, e.g. ``{"actor": [...], "critic": [...]}``.
        obs_set: ``"actor"`` or ``"critic"``.
        output_dim: Action size (actor) or 1 (critic).
        spec: The behaviour's NetworkSpec; its encoders are built afresh for this model.
        activation: Activation of the fusion and trunk layers (paper: ReLU).
        obs_normalization: Not supported (encoders see raw observations); must be False.
        distribution_cfg: rsl-rl distribution config (actor only).
        shared: Use the shared layout.
        cnns: The actor's SharedBody (the critic of the shared layout; rsl-rl passes it).
        legacy_uint8_scale: Divide uint8 observations by 255 twice (hand-regard runs trained
            before the input-scale fix; see :func:`as_float`).
        init: ``torch`` (PyTorch's default initialisation) or ``orthogonal``.
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
        shared: bool = False,
        cnns: SharedBody | None = None,
        legacy_uint8_scale: bool = False,
        init: str = "torch",
    ) -> None:
        if obs_normalization:
            raise ValueError("MultiSenseModel does not normalise observations; encoders do")
        hidden = tuple(spec.fusion_dims) + tuple(spec.trunk_dims)
        if not hidden:
            raise ValueError("NetworkSpec needs at least one fusion or trunk layer")
        # plain attributes, read by _get_latent_dim during super().__init__
        self.spec = spec
        self.shared = shared or cnns is not None
        self.legacy_uint8_scale = legacy_uint8_scale
        self.activation = activation
        self._given_body = [cnns] if cnns is not None else []  # a list: not registered
        # shared: rsl-rl's MLP needs a hidden layer; a 1-wide placeholder is replaced below
        super().__init__(
            obs,
            obs_groups,
            obs_set,
            output_dim,
            (1,) if self.shared else hidden,
            activation,
            False,
            distribution_cfg,
        )
        if self.shared:
            out = self.distribution.input_dim if self.distribution is not None else output_dim
            width = math.prod(out) if isinstance(out, list) else out
            head: list[nn.Module] = [nn.Linear(self._body().out_dim, width)]
            if isinstance(out, list):
                head.append(nn.Unflatten(-1, out))
            self.mlp = nn.Sequential(*head)
            if self.distribution is not None:
                self.distribution.init_mlp_weights(self.mlp)
        if init == "orthogonal":
            self._init_orthogonal()
        elif init != "torch":
            raise ValueError(f"unknown init '{init}'; valid: torch, orthogonal")

    def _init_orthogonal(self) -> None:
        """SB3's and cleanrl's initialisation: every Linear layer this model owns orthogonal with
        gain sqrt(2) and zero bias, the output layer with gain 1, then the head's own start
        (the policy's mean layer scaled to 0.01, the spread's bias) on top."""
        layers = [m for m in self.modules() if isinstance(m, nn.Linear)]
        with torch.no_grad():
            for layer in layers:
                nn.init.orthogonal_(layer.weight, math.sqrt(2.0))
                nn.init.zeros_(layer.bias)
            last = [m for m in self.mlp.modules() if isinstance(m, nn.Linear)][-1]
            nn.init.orthogonal_(last.weight, 1.0)
        if self.distribution is not None:
            self.distribution.init_mlp_weights(self.mlp)

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
        unknown = set(self.spec.normalize) - set(self.spec.encoders)
        if unknown:
            raise ValueError(f"NetworkSpec.normalize names unknown observations {sorted(unknown)}")
        if self._given_body:  # the critic borrows the actor's body, unregistered
            body = self._given_body[0]
            if body.groups != self.obs_groups:
                raise ValueError(
                    f"a shared body needs the same observations for actor and critic; got "
                    f"{body.groups} and {self.obs_groups}"
                )
            self._borrowed = [body]
            return body.out_dim
        if self.shared:
            self.body = SharedBody(
                self.spec, self.obs_shapes, self.activation, self.legacy_uint8_scale
            )
            return self.body.out_dim
        self.encoders = nn.ModuleDict(
            {g: self.spec.encoders[g].build(shape) for g, shape in self.obs_shapes.items()}
        )
        self.normalizers = nn.ModuleDict(
            {
                g: EmpiricalNormalization(shape)
                for g, shape in self.obs_shapes.items()
                if g in self.spec.normalize
            }
        )
        return sum(self.spec.encoders[g].out_dim(s) for g, s in self.obs_shapes.items())

    def _body(self) -> SharedBody:
        return self._borrowed[0] if hasattr(self, "_borrowed") else self.body

    @property
    def cnns(self) -> SharedBody | None:
        """The shared body (rsl-rl's ``share_cnn_encoders`` passes it to the critic)."""
        return self._body() if self.shared else None

    def _input(self, obs: Observations, group: str) -> torch.Tensor:
        x = as_float(obs[group], self.legacy_uint8_scale)
        return self.normalizers[group](x) if group in self.normalizers else x

    def get_latent(
        self, obs: Observations, masks: torch.Tensor | None = None, hidden_state: Any = None
    ) -> torch.Tensor:
        """Normalise the groups named in ``spec.normalize``, encode every group, concatenate
        (separate layout), or the shared body's features (shared layout).

        Returns:
            (N, latent_dim).
        """
        if self.shared:
            return self._body()(obs, id(self))
        return torch.cat([self.encoders[g](self._input(obs, g)) for g in self.obs_groups], dim=-1)

    def encode(self, obs: Observations) -> torch.Tensor:
        """:meth:`get_latent` without the shared body's reuse of results (for export)."""
        return self._body().encode(obs) if self.shared else self.get_latent(obs)

    def update_normalization(self, obs: TensorDict) -> None:
        """Update the running statistics of the normalised groups from a rollout batch (the
        shared body's by its owner only, so each batch is counted once)."""
        if self.shared:
            if not hasattr(self, "_borrowed"):
                self.body.update_normalization(obs)
            return
        for group, normalizer in self.normalizers.items():
            normalizer.update(as_float(obs[group], self.legacy_uint8_scale))  # type: ignore[operator]

    def as_jit(self) -> nn.Module:
        raise NotImplementedError(
            "use devlearn.evaluation.export (devlearn export) for MultiSenseModel"
        )

    def as_onnx(self, verbose: bool) -> nn.Module:
        raise NotImplementedError(
            "use devlearn.evaluation.export (devlearn export) for MultiSenseModel"
        )
