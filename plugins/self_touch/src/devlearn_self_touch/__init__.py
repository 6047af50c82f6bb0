"""devlearn-self-touch: the paper's Model I, self-touch via tactile novelty (sec. II-A)."""

from __future__ import annotations

from devlearn_self_touch.activity import ActivityLevel, ContactTime, Effort, TouchOnset
from devlearn_self_touch.behavior import SelfTouch
from devlearn_self_touch.config import SelfTouchConfig, default_rewards, paper_rewards
from devlearn_self_touch.evaluation import SelfTouchEvaluator
from devlearn_self_touch.rewards import (
    Balance,
    ContactNovelty,
    DiversityMilestones,
    TouchNovelty,
    f_decay,
)

__all__ = [
    "ActivityLevel",
    "Balance",
    "ContactNovelty",
    "ContactTime",
    "TouchOnset",
    "DiversityMilestones",
    "Effort",
    "SelfTouch",
    "SelfTouchConfig",
    "SelfTouchEvaluator",
    "TouchNovelty",
    "default_rewards",
    "f_decay",
    "paper_rewards",
]
