"""NetworkSpec: how a behaviour's policy and value networks are assembled from per-sense encoders.

Kept apart from :mod:`devlearn.api.behavior` because the core's network builder and distribution
read it, and its one check of the spread settings lives beside it. Plugins import it from
``devlearn``.
"""

from __future__ import annotations

from dataclasses import dataclass

from devlearn.api.sensors import SensorEncoder


@dataclass
class NetworkSpec:
    """How to assemble the policy and value networks from per-sense encoders.

    Each observation named in ``encoders`` goes through its encoder; the features are
    concatenated, passed through ``fusion_dims`` (Linear+ReLU each), then ``trunk_dims``
    (Linear+ReLU each). The policy head is a Gaussian with ``tanh`` mean and state-dependent
    ``softplus`` standard deviation (paper, sec. II-A4); the value head is one linear layer.
    With ``share`` (the default, the paper's layout) policy and value use one set of encoders,
    fusion and trunk and differ only in their heads; without it each network gets its own copy
    of everything. The run config's ``network.layout`` may override the choice.

    Attributes:
        encoders: Observation name -> encoder. Every observation in the behaviour's actor and
            critic groups must have one.
        fusion_dims: Fusion layers after concatenation (paper Model I: ``(512,)``).
        trunk_dims: Trunk layers before the heads (paper Model I: ``(256, 256)``).
        init_std: Initial standard deviation of the policy (softplus bias is set to match).
        max_std: Upper bound on the policy's standard deviation (a sigmoid replaces the
            softplus); 0: unbounded, as in the paper.
        normalize: Observations standardised by a running mean and variance before their
            encoder (rsl-rl's ``EmpiricalNormalization``, updated during rollouts), e.g.
            ``("proprioception",)`` whose joint velocities and torques have mixed scales.
        share: One set of encoders, fusion and trunk feeds both heads (paper: the trunk
            "feeds both policy and value heads"); False: separate actor and critic networks.
        actor: The observations the actor sees (rsl-rl's ``actor`` set), or None: all.
        critic: The observations the critic sees (``critic``), or None: all.
    """

    encoders: dict[str, SensorEncoder]
    fusion_dims: tuple[int, ...] = (512,)
    trunk_dims: tuple[int, ...] = (256, 256)
    init_std: float = 0.5
    max_std: float = 0.0
    normalize: tuple[str, ...] = ()
    share: bool = True
    actor: tuple[str, ...] | None = None
    critic: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        check_spread(self.init_std, self.max_std)

    def obs_groups(self, observation_names: list[str]) -> dict[str, list[str]]:
        """rsl-rl's observation sets: ``actor`` and ``critic`` -> the names of
        ``observation_names`` each sees (:attr:`actor`, :attr:`critic`), in that order."""

        def seen(names: tuple[str, ...] | None) -> list[str]:
            return [n for n in observation_names if names is None or n in names]

        return {"actor": seen(self.actor), "critic": seen(self.critic)}


def check_spread(init_std: float, max_std: float, min_std: float = 1e-3) -> None:
    """The one check of the policy's spread settings (NetworkSpec and the distribution).

    Raises:
        ValueError: ``init_std`` not above ``min_std``, or ``max_std`` neither 0 (unbounded)
            nor above ``init_std``.
    """
    if init_std <= min_std:
        raise ValueError(f"init_std must exceed min_std={min_std}, got {init_std}")
    if max_std < 0 or 0 < max_std <= init_std:
        raise ValueError(
            f"max_std must be 0 (unbounded) or above init_std={init_std}, got {max_std}"
        )
