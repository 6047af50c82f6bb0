"""``check_learned_reward``: the conformance check of a learned reward (re-exported by
:mod:`devlearn.testing`, where plugin authors find it)."""

from __future__ import annotations

import dataclasses
import io

import numpy as np
import torch

from devlearn.api.learned import LearnedReward, LearnedRewardConfig, Transitions
from devlearn.testing.values import require


def random_transitions(
    shapes: dict[str, tuple[int, ...]], action_dim: int, size: int, seed: int
) -> Transitions:
    """Random transitions: uint8 images for (H, W, C) shapes, normal floats otherwise.

    Returns:
        :class:`~devlearn.api.learned.Transitions` of ``size`` rows: observations (size, *shape)
        per name, actions (size, action_dim) uniform in [-1, 1], next observations likewise.
    """
    gen = torch.Generator().manual_seed(seed)

    def draw() -> dict[str, torch.Tensor]:
        return {
            name: torch.randint(0, 256, (size, *shape), generator=gen, dtype=torch.uint8)
            if len(shape) == 3
            else torch.randn(size, *shape, generator=gen)
            for name, shape in shapes.items()
        }

    actions = torch.rand(size, action_dim, generator=gen) * 2 - 1
    return Transitions(draw(), actions, draw())


def check_learned_reward(
    term_cls: type[LearnedReward],
    observation_shapes: dict[str, tuple[int, ...]] | None = None,
    action_dim: int = 3,
    batch_size: int = 32,
    seed: int = 0,
) -> LearnedReward:
    """Check a learned reward: class contract, shapes, training, and a save/restore.

    Builds the term on random transitions (``observation_shapes`` default: a (6,) vector
    ``proprioception`` and an (8, 8, 3) ``eyes`` image) and checks: a docstring, a
    lower_snake_case ``name``, a :class:`~devlearn.LearnedRewardConfig` dataclass; rewards
    (B,) and finite, the same when asked twice; an update changes trainable parameters and
    reports finite ``raw``, ``loss`` and ``weight``; the state (model, optimiser, scale)
    survives ``torch.save`` / ``torch.load(weights_only=True)`` into a fresh instance, which
    then rewards and trains exactly like the original.

    Returns:
        The trained term.
    """
    from devlearn.plugins import PLUGIN_NAME

    shapes = observation_shapes or {"proprioception": (6,), "eyes": (8, 8, 3)}
    require(bool(term_cls.__doc__), f"{term_cls.__name__} needs a docstring")
    name = getattr(term_cls, "name", None)
    require(isinstance(name, str) and bool(PLUGIN_NAME.match(name)), "name: lower_snake_case")
    config_cls = term_cls.config_class
    require(
        dataclasses.is_dataclass(config_cls) and issubclass(config_cls, LearnedRewardConfig),
        "config_class must be a dataclass subclassing LearnedRewardConfig",
    )
    torch.manual_seed(seed)
    term = term_cls(config_cls(), shapes, action_dim)
    batch = random_transitions(shapes, action_dim, batch_size, seed)
    term.observe(batch)
    with torch.no_grad():
        first, second = term.compute_reward(batch), term.compute_reward(batch)
    require(
        tuple(first.shape) == (batch_size,),
        f"compute_reward gave {tuple(first.shape)}, expected ({batch_size},)",
    )
    require(bool(torch.isfinite(first).all()), "compute_reward gave NaN or inf")
    require(torch.equal(first, second), "compute_reward changed on the same batch")
    before = [p.detach().clone() for p in term.model.parameters() if p.requires_grad]
    reward, log = term.update(batch, env_steps=0)
    require(tuple(reward.shape) == (batch_size,), "update must return a (B,) reward")
    require(set(log) >= {"raw", "loss", "weight"}, f"update log lacks raw/loss/weight: {log}")
    require(all(np.isfinite(v) for v in log.values()), f"non-finite update log {log}")
    after = [p.detach() for p in term.model.parameters() if p.requires_grad]
    require(any(not torch.equal(a, b) for a, b in zip(before, after)), "update trained nothing")
    buffer = io.BytesIO()
    torch.save(term.state_dict(), buffer)
    buffer.seek(0)
    fresh = term_cls(config_cls(), shapes, action_dim)
    fresh.load_state_dict(torch.load(buffer, weights_only=True))
    later = random_transitions(shapes, action_dim, batch_size, seed + 1)
    results = []
    for copy in (term, fresh):
        torch.manual_seed(seed + 2)  # the same mini-batch order for both
        reward, _ = copy.update(later, env_steps=batch_size)
        results.append((reward, [p.detach().clone() for p in copy.model.parameters()]))
    require(torch.equal(results[0][0], results[1][0]), "restored term rewards differently")
    for a, b in zip(results[0][1], results[1][1]):
        require(torch.equal(a, b), "restored term trains differently (optimiser state lost?)")
    return term
