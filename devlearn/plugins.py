"""Plugin discovery: load entry points, call their hooks, validate what they register.

There is no module-level plugin manager: each :class:`PluginRegistry` builds its own, so tests
(and tools) can build registries from any list of plugins.
"""

from __future__ import annotations

import dataclasses
import importlib.metadata as metadata
import inspect
import json
import os
import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import pluggy

from devlearn.api import hookspecs
from devlearn.api.behavior import Behavior
from devlearn.api.errors import UsageError
from devlearn.api.json_files import read_json
from devlearn.files import write_text_atomically

if TYPE_CHECKING:  # torch-based: imported when a plugin registers one (it has loaded torch)
    from devlearn.api.learned import LearnedReward

ENTRY_POINT_GROUP = "devlearn"
DISABLE_ENV = "DEVLEARN_DISABLE_PLUGINS"
PLUGIN_NAME = re.compile(r"^[a-z][a-z0-9_]*$")
"""What a registered behaviour's or learned reward's ``name`` must match (lower_snake_case)."""


def settings_path() -> Path:
    """Return the file that remembers disabled plugins (``$DEVLEARN_CONFIG_DIR/plugins.json``)."""
    base = os.environ.get("DEVLEARN_CONFIG_DIR") or Path.home() / ".config" / "devlearn"
    return Path(base) / "plugins.json"


def _saved_disabled(path: Path) -> set[str]:
    """The plugin names the settings file ``path`` disables; none where it is missing or
    unreadable (:func:`~devlearn.api.json_files.read_json`) or holds no list of names."""
    if not path.exists():
        return set()
    try:
        data = read_json(path)
    except UsageError:
        return set()
    names = data.get("disabled", []) if isinstance(data, dict) else []
    return {n for n in names if isinstance(n, str)} if isinstance(names, list) else set()


def disabled_plugins() -> set[str]:
    """Names disabled by ``DEVLEARN_DISABLE_PLUGINS`` (comma-separated) or the settings file."""
    names = {n.strip() for n in os.environ.get(DISABLE_ENV, "").split(",") if n.strip()}
    return names | _saved_disabled(settings_path())


def set_plugin_disabled(name: str, disabled: bool) -> Path:
    """Persistently disable (or re-enable) a plugin by name; return the settings file."""
    path = settings_path()
    current = _saved_disabled(path)
    current = current | {name} if disabled else current - {name}
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomically(path, json.dumps({"disabled": sorted(current)}, indent=2) + "\n")
    return path


@dataclass
class PluginInfo:
    """What one plugin is and what it registered."""

    name: str
    distribution: str
    version: str
    behaviors: list[str] = field(default_factory=list)
    learned_rewards: list[str] = field(default_factory=list)
    hooks: list[str] = field(default_factory=list)
    disabled: bool = False
    error: str | None = None

    def to_json(self) -> dict[str, Any]:
        """Return a JSON-ready dict (keys: name, distribution, version, behaviors, hooks, ...)."""
        return dataclasses.asdict(self)


@dataclass
class PluginSource:
    """A plugin to load: a name, a loader returning its module or object, and its origin."""

    name: str
    load: Any
    distribution: str = "unknown"
    version: str = "unknown"


def entry_point_sources() -> list[PluginSource]:
    """Return the plugins installed under the ``devlearn`` entry-point group."""
    sources = []
    for ep in metadata.entry_points(group=ENTRY_POINT_GROUP):
        dist = getattr(ep, "dist", None)
        sources.append(
            PluginSource(
                name=ep.name,
                load=ep.load,
                distribution=dist.metadata["Name"] if dist is not None else "unknown",
                version=dist.version if dist is not None else "unknown",
            )
        )
    return sorted(sources, key=lambda s: s.name)


_T = TypeVar("_T")


def _registered_name(cls: object, base: type, hook: str, kind: str) -> str:
    """The name of ``cls``, which hook ``hook`` registers: a TypeError unless ``cls`` is a
    subclass of ``base`` (``kind`` in the message) with a lower_snake_case ``name``."""
    if not (inspect.isclass(cls) and issubclass(cls, base)):
        raise TypeError(f"{hook} got {cls!r}, not {kind}")
    name = getattr(cls, "name", None)
    if not isinstance(name, str) or not PLUGIN_NAME.match(name):
        raise TypeError(f"{cls.__name__}.name must be a lower_snake_case string")
    return name


def _named(table: dict[str, _T], kind: str, name: str, none: str) -> _T:
    """``table[name]``, or a UsageError naming the valid ones (``none`` when there are none)."""
    if name not in table:
        installed = ", ".join(sorted(table)) or none
        raise UsageError(f"unknown {kind} '{name}'; installed: {installed}")
    return table[name]


class PluginRegistry:
    """Loads plugins, calls their hooks and holds what they registered.

    A plugin that fails to import, implements a hook with a wrong signature or an unknown hook,
    raises inside a hook, or registers something invalid is recorded with its name and
    distribution in :attr:`plugins` (``error``) and :attr:`errors`; the others still work.

    Args:
        sources: Plugins to load (default: installed entry points).
        disabled: Plugin names to skip (default: :func:`disabled_plugins`).
    """

    def __init__(
        self, sources: Iterable[PluginSource] | None = None, disabled: Iterable[str] | None = None
    ) -> None:
        self.plugins: dict[str, PluginInfo] = {}
        self.errors: list[str] = []
        self._behaviors: dict[str, type[Behavior]] = {}
        self._learned: dict[str, type[LearnedReward]] = {}
        self._owner: dict[tuple[str, str], str] = {}
        self._pm = pluggy.PluginManager("devlearn")
        self._pm.add_hookspecs(hookspecs)
        skip = set(disabled_plugins() if disabled is None else disabled)
        for source in entry_point_sources() if sources is None else sources:
            info = PluginInfo(source.name, source.distribution, source.version)
            self.plugins[source.name] = info
            if source.name in skip:
                info.disabled = True
                continue
            try:
                self._load(source, info)
            except Exception as exc:  # a broken plugin must never stop the others
                self._fail(info, f"{type(exc).__name__}: {exc}")

    # --- loading --------------------------------------------------------------------------
    def _fail(self, info: PluginInfo, message: str) -> None:
        info.error = message
        self.errors.append(f"plugin '{info.name}' ({info.distribution}): {message}")

    def _load(self, source: PluginSource, info: PluginInfo) -> None:
        module = source.load() if callable(source.load) else source.load
        spec_names = {n for n in dir(hookspecs) if n.startswith("register_")}
        for attr in dir(module):
            value = getattr(module, attr, None)
            if callable(value) and hasattr(value, "devlearn_impl") and attr not in spec_names:
                valid = ", ".join(sorted(spec_names))
                raise TypeError(f"unknown hook '{attr}'; valid hooks: {valid}")
        self._pm.register(module, name=source.name)  # validates hook signatures
        for hook_name in sorted(spec_names):
            caller = getattr(self._pm.hook, hook_name)
            for impl in caller.get_hookimpls():
                if impl.plugin_name != source.name:
                    continue
                info.hooks.append(hook_name)
                register = getattr(self, "_" + hook_name)(info)
                impl.function(register=register)

    def _claim(self, kind: str, name: str, info: PluginInfo) -> bool:
        """Record that ``info`` owns ``kind`` ``name``; on a clash report both plugins."""
        other = self._owner.get((kind, name))
        if other is not None:
            self.errors.append(
                f"plugin '{info.name}' ({info.distribution}): {kind} '{name}' is already "
                f"registered by plugin '{other}'; ignoring this one"
            )
            return False
        self._owner[(kind, name)] = info.name
        return True

    def _register_behaviors(self, info: PluginInfo) -> Callable[[type], None]:
        def register(behavior: type) -> None:
            name = _registered_name(behavior, Behavior, "register_behaviors", "a Behavior subclass")
            if not dataclasses.is_dataclass(getattr(behavior, "config_class", None)):
                raise TypeError(f"{behavior.__name__}.config_class must be a dataclass")
            if self._claim("behavior", name, info):
                self._behaviors[name] = behavior
                info.behaviors.append(name)

        return register

    def _register_learned_rewards(self, info: PluginInfo) -> Callable[[type], None]:
        def register(term: type) -> None:
            from devlearn.api.learned import LearnedReward, LearnedRewardConfig

            name = _registered_name(
                term, LearnedReward, "register_learned_rewards", "a LearnedReward"
            )
            config = getattr(term, "config_class", None)
            if not (inspect.isclass(config) and issubclass(config, LearnedRewardConfig)):
                raise TypeError(f"{term.__name__}.config_class must subclass LearnedRewardConfig")
            if self._claim("learned reward", name, info):
                self._learned[name] = term
                info.learned_rewards.append(name)

        return register

    # --- lookup ---------------------------------------------------------------------------
    def behaviors(self) -> dict[str, type[Behavior]]:
        """Return every registered behaviour, name -> class, sorted by name."""
        return dict(sorted(self._behaviors.items()))

    def behavior(self, name: str) -> type[Behavior]:
        """Return the behaviour class called ``name``; raise UsageError listing the valid ones."""
        return _named(self._behaviors, "behavior", name, "none (install a plugin)")

    def create(self, name: str, config: Any | None = None) -> Behavior:
        """Instantiate behaviour ``name`` with ``config`` (its default when None).

        A ``ValueError`` or ``TypeError`` from the behaviour's config validation becomes a
        :class:`UsageError` naming the behaviour, so the CLI reports one clear line.
        """
        cls = self.behavior(name)
        try:
            return cls(config if config is not None else cls.config_class())
        except (ValueError, TypeError) as exc:
            raise UsageError(f"invalid config for behavior '{name}': {exc}") from exc

    def learned_rewards(self) -> dict[str, type[LearnedReward]]:
        """Return every registered learned reward, name -> class, sorted by name."""
        return dict(sorted(self._learned.items()))

    def learned_reward(self, name: str) -> type[LearnedReward]:
        """Return the learned reward called ``name``; raise UsageError listing the valid ones."""
        return _named(self._learned, "learned reward", name, "none (install devlearn-curiosity)")

    def plugin_of(self, behavior_name: str) -> PluginInfo:
        """Return the plugin that registered a behaviour."""
        return self.plugins[self._owner[("behavior", behavior_name)]]
