"""The Curriculum interface: training stages driven by the global step count."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass
class Stage:
    """One curriculum stage.

    Attributes:
        name: Short name shown in logs and the progress bar (e.g. ``"fixed_pose"``).
        steps: Environment steps (summed over all environments) this stage lasts; ``None``
            means until the end of training.
        options: Options the environment and behaviour read while the stage is active. The
            core understands ``random_pose`` (bool: random initial joint angles at reset);
            behaviours may define their own (e.g. ``active_arms``).
    """

    name: str
    steps: int | None
    options: dict[str, Any] = field(default_factory=dict)


class Curriculum:
    """A sequence of stages switched by training progress (total environment steps).

    The runner calls :meth:`update` with the global step count before each rollout; when the
    stage changes, the new options are sent to every environment. The state (current stage and
    step) is saved in checkpoints and restored on resume.
    """

    def __init__(self, stages: list[Stage]) -> None:
        if not stages:
            raise ValueError("a curriculum needs at least one stage")
        for stage in stages[:-1]:
            if stage.steps is None or stage.steps < 0:
                raise ValueError(
                    f"stage '{stage.name}' needs a non-negative step count (only the last "
                    "stage may last until the end)"
                )
        self.stages = list(stages)
        self.step = 0
        self.index = 0

    def stage_index_at(self, step: int) -> int:
        """Return the index of the stage active at global environment step ``step``."""
        boundary = 0
        for i, stage in enumerate(self.stages[:-1]):
            boundary += int(stage.steps)  # type: ignore[arg-type]
            if step < boundary:
                return i
        return len(self.stages) - 1

    def update(self, step: int) -> bool:
        """Advance to global step ``step``; return True when the stage changed."""
        self.step = int(step)
        new_index = self.stage_index_at(self.step)
        changed = new_index != self.index
        self.index = new_index
        return changed

    @property
    def stage(self) -> Stage:
        """The active stage."""
        return self.stages[self.index]

    def state_dict(self) -> dict[str, Any]:
        """Return the resumable state (step and stage index)."""
        return {"step": self.step, "index": self.index, "names": [s.name for s in self.stages]}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore :meth:`state_dict`'s output."""
        self.step = int(state["step"])
        self.index = int(state["index"])
