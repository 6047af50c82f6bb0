"""devlearn-hand-regard: the paper's Model II, hand regard via visual rewards (sec. II-B)."""

from __future__ import annotations

from devlearn_hand_regard.behavior import HandRegard
from devlearn_hand_regard.config import HandRegardConfig

__all__ = ["HandRegard", "HandRegardConfig"]
