"""Training: networks, the PPO runner and ``train()`` (the run config: :mod:`devlearn.config`)."""

from __future__ import annotations

import sys
import types
from typing import Any

from devlearn.lazy import lazy_getattr

# Loaded on first use (PEP 562): the light modules of this package (checkpoint names) are
# imported by commands that must not pay for torch.
_PUBLIC = {
    "TrainResult": "devlearn.training.train",
    "train": "devlearn.training.train",
}


__getattr__ = lazy_getattr("devlearn.training", _PUBLIC, globals())


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))


class _Package(types.ModuleType):
    """``devlearn.training.train`` stays the function, as when this package imported it
    eagerly, also once its module is imported (the import system then sets the module as an
    attribute of its package)."""

    def __setattr__(self, name: str, value: Any) -> None:
        if name == "train" and isinstance(value, types.ModuleType):
            value = getattr(value, name)
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package


__all__ = ["TrainResult", "train"]
