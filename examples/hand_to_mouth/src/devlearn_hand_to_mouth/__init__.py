"""An example third-party devlearn plugin: the infant learns to bring a hand to its mouth."""

from __future__ import annotations

from devlearn_hand_to_mouth.behavior import HandToMouth, HandToMouthConfig

__all__ = ["HandToMouth", "HandToMouthConfig"]
