"""resolve_config(): the one path from what a command asks for (a fresh run, ``--resume``,
``--from``, ``--config``, ``--preset``, ``--set``) to a checked :class:`RunConfig`."""

from __future__ import annotations

import copy
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from devlearn.api.errors import UsageError
from devlearn.api.json_files import read_json_object
from devlearn.config.checks import check_config
from devlearn.config.growth import keep_growth_on_resume
from devlearn.config.run_config import (
    RunConfig,
    apply_preset,
    build_behavior,
    finish_config,
    from_dict,
    scale_to_length,
    start_config,
    to_dict,
)
from devlearn.config.values import apply_overrides, override_keys
from devlearn.files import write_text_atomically

if TYPE_CHECKING:
    from devlearn.api.behavior import Behavior
    from devlearn.plugins import PluginRegistry

CONFIG_FILE = "config.json"
"""The resolved config a run writes next to its checkpoints (what ``--resume`` reads)."""
RUN_CONFIG_FILE = "run_config.json"
"""The resolved config a sweep writes into a run's folder and starts the run from
(``devlearn run BEHAVIOR --config RUN/run_config.json``)."""


class CheckpointReader(Protocol):
    """Reads the config a checkpoint was trained with, for ``--from`` (the one request that
    needs a checkpoint): :func:`devlearn.training.checkpoint.checkpoint_config`.

    Passed in by the caller, because reading a checkpoint is the training layer's (torch,
    the checkpoint format) and config sits below it: resolving any other request loads no
    torch (``devlearn config`` stays light).
    """

    def __call__(self, path: str, registry: PluginRegistry, behavior: str) -> RunConfig:
        """The config checkpoint ``path`` was trained with (unchecked), which must train
        ``behavior`` (empty: any installed behaviour).

        Raises:
            UsageError: A missing, corrupt or incomplete checkpoint, or one of another
                behaviour.
        """
        ...


@dataclass
class RunRequest:
    """What a command asks for; :func:`resolve_config` turns it into a RunConfig.

    At most one of ``resume``, ``start_from``, ``config_file`` and ``saved`` names where the
    config starts; none: a fresh run (the core defaults < the behaviour's ``train_defaults()``).
    Then, in this order: ``preset`` (not with ``resume`` or a saved config), ``top``,
    ``overrides``.
    """

    behavior: str = ""
    """The behaviour to run; empty with ``resume``: the one the run trains."""
    overrides: list[str] = field(default_factory=list)
    """``--set KEY=VALUE`` items."""
    preset: str = ""
    """A name from the behaviour's ``presets`` (``--preset``)."""
    top: dict[str, Any] = field(default_factory=dict)
    """Top-level fields set by options (``total_steps``, ``num_envs``, ``workers``, ``seed``,
    ``device``, ``logger``); None values are skipped."""
    out_dir: str = ""
    """``--out``; not with ``resume`` (a resumed run stays in its folder)."""
    resume: str = ""
    """A run folder whose ``config.json`` a resumed run keeps (``--resume``)."""
    start_from: str = ""
    """A checkpoint whose config a new run starts from (``--from``)."""
    config_file: str = ""
    """A resolved config file (``--config``: a sweep's ``run_config.json``, a run's
    ``config.json``) a new run starts from."""
    saved: dict[str, Any] | None = None
    """A saved config given as data (read as :func:`~devlearn.config.run_config.from_dict`
    reads one: keys it lacks take the values old runs were trained with)."""


@dataclass
class ResolvedRun:
    """A resolved run: its checked config and the behaviour built on it (the one instance the
    run trains, so the behaviour is built, and checks its config, once per run)."""

    cfg: RunConfig
    """The run config, checked."""
    behavior: Behavior
    """The behaviour built on ``cfg.behavior``."""
    notes: list[str] = field(default_factory=list)
    """What resolving decided that the user did not say (a resumed growing run's schedule kept
    over its steps), for the command to print."""


def resolve_config(
    request: RunRequest,
    registry: PluginRegistry,
    read_checkpoint: CheckpointReader | None = None,
) -> RunConfig:
    """The run config ``request`` asks for, checked: :func:`resolve_run`'s config, for a
    command that needs no behaviour (``devlearn config``, a sweep's plan)."""
    return resolve_run(request, registry, read_checkpoint).cfg


def resolve_run(
    request: RunRequest,
    registry: PluginRegistry,
    read_checkpoint: CheckpointReader | None = None,
) -> ResolvedRun:
    """The run config ``request`` asks for, checked (every value in bounds, the learner's
    head, spread bounds and decision rate, the behaviour's config and ``network()``), with the
    behaviour built on it, ready for :func:`~devlearn.training.train.train`. Every command
    that builds a run's config builds it here (``devlearn run``, ``config``, ``sweep``,
    ``eval``'s baselines, ``bench``, the Gymnasium envs), so each checks what ``devlearn run``
    checks.

    - fresh: defaults < the behaviour's ``train_defaults()`` < preset < top < overrides;
    - ``resume``: the run's ``config.json`` < top < overrides; the seed stays the run's;
    - ``start_from``: the checkpoint's config < preset < top < overrides; ``start_from``
      records the checkpoint and ``out_dir`` is ``request.out_dir``;
    - ``config_file`` / ``saved``: that config < top < overrides.

    ``read_checkpoint`` reads ``start_from``'s config
    (:func:`devlearn.training.checkpoint.checkpoint_config`); only a request with
    ``start_from`` needs it.

    Raises:
        UsageError: Options that exclude each other, an unknown behaviour or preset, a
            config or checkpoint that is unreadable or trains another behaviour, a bad
            override or value (each named with what is valid).
    """
    sources = [
        name
        for name, given in (
            ("--resume", request.resume),
            ("--from", request.start_from),
            ("--config", request.config_file),
            ("a saved config", request.saved is not None),
        )
        if given
    ]
    if request.resume and (request.preset or request.start_from):
        raise UsageError("--resume keeps the run's config; --preset and --from start new runs")
    if len(sources) > 1:
        raise UsageError(f"{' and '.join(sources)} exclude each other")
    if request.resume and request.preset:
        raise UsageError("--resume keeps the run's config; --preset and --from start new runs")
    if request.resume and request.out_dir:
        raise UsageError("--out and --resume exclude each other (a resumed run stays put)")
    if (request.config_file or request.saved is not None) and request.preset:
        raise UsageError("--config starts from a resolved config; --preset does not apply to it")
    top = {k: v for k, v in request.top.items() if v is not None}
    behavior: Behavior | None = None
    notes: list[str] = []
    placed = {**top, "out_dir": request.out_dir} if request.out_dir else top
    if request.resume:
        cfg = _resumed(request, registry, top, notes)
    elif request.start_from:
        if read_checkpoint is None:
            raise TypeError(
                "resolve_config: a request with start_from needs read_checkpoint "
                "(devlearn.training.checkpoint.checkpoint_config)"
            )
        cfg = _branched(request, registry, top, read_checkpoint)
    elif request.config_file or request.saved is not None:
        data = request.saved
        if data is None:
            data = read_config_file(request.config_file)
        source = request.config_file or "the saved config"
        cfg = _from_saved(data, request, registry, source, new_run=bool(request.config_file))
        apply_overrides(cfg, placed)
        apply_overrides(cfg, request.overrides)
    else:  # fresh: as fresh_config, keeping the behaviour it builds
        behavior_cls = registry.behavior(request.behavior)
        cfg, explicit = start_config(behavior_cls, request.preset, **placed)
        explicit |= override_keys(request.overrides)
        apply_overrides(cfg, request.overrides)
        behavior = build_behavior(cfg, behavior_cls)
        scale_to_length(cfg, behavior, explicit)
    if behavior is None:
        behavior = build_behavior(cfg, registry.behavior(cfg.behavior_name))
    finish_config(cfg, behavior)
    check_config(cfg)
    return ResolvedRun(cfg, behavior, notes)


def read_config_file(path: str | Path) -> dict[str, Any]:
    """A saved run config (``config.json``, ``run_config.json``) as a dict, read by the guarded
    reader (:func:`~devlearn.api.json_files.read_json_object`).

    Raises:
        UsageError: The file is missing, not a regular file, too large, not JSON, nested too
            deeply, or not a JSON object.
    """
    return read_json_object(path, "a run config")


def write_config_file(cfg: RunConfig, path: str | Path) -> Path:
    """Write ``cfg`` as JSON (every resolved value) to ``path`` atomically (a kill leaves the
    previous file, which ``--resume`` reads, or the new one); return the path."""
    path = Path(path)
    write_text_atomically(path, json.dumps(to_dict(cfg), indent=2) + "\n")
    return path


def load_run_config(run_dir: str | Path, registry: PluginRegistry) -> RunConfig:
    """A run folder's ``config.json`` as written (unchecked: what ``--resume`` starts from).

    Raises:
        UsageError: The file is missing or unreadable, or names no installed behaviour.
    """
    data = read_config_file(Path(run_dir) / CONFIG_FILE)
    return from_dict(data, registry.behavior(data.get("behavior_name", "")))


def _from_saved(
    data: dict[str, Any],
    request: RunRequest,
    registry: PluginRegistry,
    source: str,
    new_run: bool = False,
) -> RunConfig:
    """``data`` read for its behaviour, which must be the requested one (if one is; a config
    that names none is read for the requested one); ``new_run``: a new run's config file, whose
    missing keys take today's defaults (:func:`~devlearn.config.run_config.from_dict`)."""
    name = data.get("behavior_name") or request.behavior
    if request.behavior and name != request.behavior:
        raise UsageError(f"{source} trains '{name}', not '{request.behavior}'")
    return from_dict(data, registry.behavior(name), new_run)


def _resumed(
    request: RunRequest, registry: PluginRegistry, top: dict[str, Any], notes: list[str]
) -> RunConfig:
    run_dir = Path(request.resume)
    if not run_dir.is_dir():
        raise UsageError(f"run directory {run_dir} does not exist")
    cfg = _from_saved(read_config_file(run_dir / CONFIG_FILE), request, registry, f"run {run_dir}")
    saved = copy.deepcopy(cfg)
    recorded_seed = cfg.seed
    apply_overrides(cfg, top)
    apply_overrides(cfg, request.overrides)
    if note := keep_growth_on_resume(saved, cfg, str(run_dir)):  # the age never goes back
        notes.append(note)
    if cfg.seed != recorded_seed:
        raise UsageError(
            f"run {run_dir} was trained with seed {recorded_seed}, which a resumed run keeps "
            "(its random states continue from the checkpoint); for another seed start a new "
            f"run from its checkpoint: --from {run_dir / 'checkpoint_latest.pt'} "
            f"--seed {cfg.seed} --out NEW_DIR"
        )
    return cfg


def _branched(
    request: RunRequest,
    registry: PluginRegistry,
    top: dict[str, Any],
    read_checkpoint: CheckpointReader,
) -> RunConfig:
    cfg = read_checkpoint(str(request.start_from), registry, request.behavior)
    if request.preset:
        apply_preset(cfg, registry.behavior(cfg.behavior_name), request.preset)
    apply_overrides(cfg, top)
    apply_overrides(cfg, request.overrides)
    cfg.out_dir = request.out_dir
    cfg.start_from = str(request.start_from)
    return cfg
