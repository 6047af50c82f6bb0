"""rsl-rl's PPO with one optimiser entry per parameter (no double Adam steps on shared tensors)."""

from __future__ import annotations

import warnings
from itertools import chain
from typing import TYPE_CHECKING, Any

import torch
import torch.nn as nn
from rsl_rl.algorithms import PPO
from rsl_rl.utils import reduce_gradients_in_buckets

if TYPE_CHECKING:
    from rsl_rl.models import MLPModel
    from rsl_rl.storage import RolloutStorage


def unique_parameters(*modules: nn.Module) -> list[nn.Parameter]:
    """Parameters of all ``modules``, each tensor once, in first-seen order."""
    seen: set[int] = set()
    params = []
    for param in chain.from_iterable(m.parameters() for m in modules):
        if id(param) not in seen:
            seen.add(id(param))
            params.append(param)
    return params


def _multi_tensor(optimizer: type[torch.optim.Optimizer]) -> dict[str, Any]:
    """``{"foreach": True}`` for Adam and AdamW: torch steps CPU parameters one tensor at a
    time from Python (``_single_tensor_adam``) unless told otherwise; the multi-tensor form
    runs the same elementwise operations in the same order (bit for bit the same parameters,
    ``tests/training/test_learner.py``) with one call per operation for all tensors."""
    return {"foreach": True} if optimizer in (torch.optim.Adam, torch.optim.AdamW) else {}


class UniqueParamPPO(PPO):
    """PPO whose optimiser holds every parameter once.

    rsl-rl 5.5.1 builds its optimiser over ``chain(actor.parameters(), critic.parameters())``:
    a tensor shared by actor and critic would then get two Adam steps per mini-batch. In our
    shared layout the critic holds the actor's body without registering it (its
    ``parameters()`` are its head alone), so each tensor appears once anyway; but anything
    else that shares registered modules (rsl-rl's own ``share_cnn_encoders`` with its CNN
    models, a behaviour's own sharing) would hit the trap, so the optimiser is rebuilt here
    over unique parameters, and gradients are all-reduced once per tensor when distributed.
    Gradient clipping stays rsl-rl's, per network: the shared body is clipped with the
    policy head (its gradient holds both losses), the value head on its own. ``adam_eps`` is the
    optimiser's epsilon (``ppo.adam_eps``).
    """

    optimizer: torch.optim.Optimizer

    def __init__(
        self,
        actor: MLPModel,
        critic: MLPModel,
        storage: RolloutStorage,
        *args: Any,
        adam_eps: float = 1e-8,
        **kwargs: Any,
    ) -> None:
        with warnings.catch_warnings():  # the parent's optimiser, replaced below, may warn
            warnings.filterwarnings("ignore", message=".*duplicate parameters")
            super().__init__(actor, critic, storage, *args, **kwargs)
        # the parent's optimiser class (Adam...) takes lr; torch's Optimizer base does not
        self.optimizer = type(self.optimizer)(  # type: ignore[call-arg]
            unique_parameters(self.actor, self.critic),
            lr=self.learning_rate,
            eps=adam_eps,
            **_multi_tensor(type(self.optimizer)),
        )

    def load(self, loaded_dict: dict, load_cfg: dict | None, strict: bool) -> bool:
        """rsl-rl's load; the optimiser keeps its multi-tensor steps (a state saved before
        them carries ``foreach: None`` in its parameter groups, which loading restores)."""
        resumed = super().load(loaded_dict, load_cfg, strict)
        for group in self.optimizer.param_groups:
            group.update(_multi_tensor(type(self.optimizer)))
        return resumed

    def set_learning_rate(self, lr: float) -> None:
        """The optimiser's step size from now on (a resumed run's fixed rate, or
        ``ppo.schedule=linear``'s next)."""
        self.learning_rate = lr
        for group in self.optimizer.param_groups:
            group["lr"] = lr

    def reduce_parameters(self) -> None:
        """Average gradients across ranks, each tensor once."""
        modules = [self.actor, self.critic] + ([self.rnd] if self.rnd else [])
        reduce_gradients_in_buckets(
            unique_parameters(*modules), self.gpu_world_size, self.grad_reduce_bucket_mb
        )
