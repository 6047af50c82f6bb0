"""devlearn-curiosity: learned intrinsic rewards (``rnd``, ``forward_model``) for any behaviour."""

from __future__ import annotations

from devlearn_curiosity.forward_model import ForwardModel, ForwardModelConfig
from devlearn_curiosity.rnd import RND, RNDConfig

__all__ = ["RND", "ForwardModel", "ForwardModelConfig", "RNDConfig"]
