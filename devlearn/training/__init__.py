"""Training: run config, networks, the PPO runner, train() and evaluate()."""

from __future__ import annotations

import sys
import types

from devlearn.lazy import lazy_getattr

# Loaded on first use (PEP 562): the light modules of this package (config, checks,
# checkpoint names) are imported by commands that must not pay for torch.
_PUBLIC = {
    "PPOConfig": "devlearn.training.config",
    "RunConfig": "devlearn.training.config",
    "default_config": "devlearn.training.config",
    "from_dict": "devlearn.training.config",
    "to_dict": "devlearn.training.config",
    "to_rsl_rl": "devlearn.training.config",
    "apply_overrides": "devlearn.training.config_values",
    "evaluate": "devlearn.training.evaluate",
    "TrainResult": "devlearn.training.train",
    "train": "devlearn.training.train",
}


__getattr__ = lazy_getattr("devlearn.training", _PUBLIC, globals())


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))


class _Package(types.ModuleType):
    """``devlearn.training.train`` and ``.evaluate`` stay the functions, as when this package
    imported them eagerly, also once their modules are imported (the import system then sets
    the module as an attribute of its package)."""

    def __setattr__(self, name: str, value) -> None:
        if name in ("train", "evaluate") and isinstance(value, types.ModuleType):
            value = getattr(value, name)
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package


__all__ = [
    "PPOConfig",
    "RunConfig",
    "TrainResult",
    "apply_overrides",
    "default_config",
    "evaluate",
    "from_dict",
    "to_dict",
    "to_rsl_rl",
    "train",
]
