"""resolve_run(): the one pipeline from what a command asks for (a fresh run, ``--resume``,
``--from``, ``--config``, ``--preset``, ``--set``) to a checked :class:`RunConfig` and the
behaviour built on it, its stages the small functions below it; reading and writing a run's
config file."""

from __future__ import annotations

import copy
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from devlearn.api.errors import UsageError
from devlearn.api.json_files import read_json_object
from devlearn.config.checks import check_config, check_resumed
from devlearn.config.run_config import RunConfig, finish_config, from_dict, new_config, to_dict
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

    At most one of ``resume``, ``start_from``, ``config_file``, ``saved`` and ``baseline``
    names where the config starts; none: a fresh run (the core defaults < the behaviour's
    ``train_defaults()``). Then, in this order: ``preset`` (not with ``resume``,
    ``config_file`` or ``saved``), ``top``, ``overrides``.
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
    baseline: bool = False
    """The config a baseline policy acts with (``devlearn eval --policy zero``, ``random``,
    ``held_random``): a saved config without values (the values a saved config lacking them
    means: ``LEGACY_FIELDS``, the behaviour's ``LEGACY_DEFAULTS``), at the decision rate of a
    new run of the behaviour (its fresh config's ``env.action_repeat``)."""


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
    """:func:`resolve_run`'s config alone, for a command that needs no behaviour
    (``devlearn config``, a sweep's plan): ``resolve_run(...).cfg``."""
    return resolve_run(request, registry, read_checkpoint).cfg


def resolve_run(
    request: RunRequest,
    registry: PluginRegistry,
    read_checkpoint: CheckpointReader | None = None,
) -> ResolvedRun:
    """The run config ``request`` asks for, checked (every value in bounds, the learner's
    head, spread bounds and decision rate, the behaviour's config and ``network()``), with the
    behaviour built on it, ready for :func:`~devlearn.training.train.train`. Every command
    that builds a run's config builds it here (``devlearn run``, ``config``, ``info``,
    ``sweep``, ``experiment``, ``eval``'s baselines, ``bench``, the Gymnasium envs), so each
    checks what ``devlearn run`` checks.

    One pipeline, its stages in this order, each a function of this module:

    1. the request's options, checked against each other (:func:`_check_request`);
    2. where the config starts (:func:`_start`): fresh, the core defaults < the behaviour's
       ``train_defaults()``; ``resume``, the run's ``config.json``; ``start_from``, the
       checkpoint's config; ``config_file`` / ``saved``, that config (a new run's file: keys
       it lacks take a fresh run's values); ``baseline``, an empty saved config at a fresh
       run's decision rate;
    3. ``preset`` (:func:`_apply_preset`; fresh and ``start_from`` only);
    4. ``top`` and ``out_dir``, then ``overrides`` (``--set``);
    5. a resumed run keeps its seed and growth schedule
       (:func:`~devlearn.config.checks.check_resumed`); a run from a checkpoint records it
       (:func:`_record_source`);
    6. the behaviour built on the config (:func:`_build_behavior`); a fresh run's run-length
       defaults (:func:`_scale_to_length`: ``run_length_defaults(total_steps)``, except the
       keys the preset or ``--set`` gave);
    7. the checks (:func:`~devlearn.config.run_config.finish_config`,
       :func:`~devlearn.config.checks.check_config`), then the :class:`ResolvedRun`.

    The walk a reader follows (``python scripts/walk_resolve.py``): from this body through
    every call named in the code within ``devlearn/``, into the stages (walked: their calls
    followed, their ``return`` statements counted), not into the tools a stage hands one job
    (opened: their files counted): setting dotted keys (``values.apply_overrides``,
    ``override_keys``), reading a saved config (``run_config.from_dict``,
    :func:`read_config_file`) and the checks (``finish_config``, ``check_config``,
    ``check_resumed``); calls on objects handed in (the registry, the behaviour, the
    checkpoint reader) are not followed. Counted so, it is 4 files (``resolve.py``,
    ``run_config.py``, ``values.py``, ``checks.py``) and 4 returns; on bb126a6, before this
    pipeline, 5 files and 8 returns (the builders in ``run_config.py``, a growth rule in
    ``growth.py``; issue #59 counted 10 files and 27 returns by a rule it does not give).
    Through the tools too (``--all``): 10 files and 77 returns, 81 on bb126a6 (the ``--set``
    language and the checks are unchanged).

    ``read_checkpoint`` reads ``start_from``'s config
    (:func:`devlearn.training.checkpoint.checkpoint_config`); only a request with
    ``start_from`` needs it.

    Raises:
        UsageError: Options that exclude each other, an unknown behaviour or preset, a
            config or checkpoint that is unreadable or trains another behaviour, a bad
            override or value (each named with what is valid).
    """
    _check_request(request)
    fresh = not (request.resume or request.start_from or request.config_file)
    fresh = fresh and request.saved is None and not request.baseline
    cfg = _start(request, registry, read_checkpoint)
    started = copy.deepcopy(cfg)  # what a resumed run's checks compare against
    behavior_cls = registry.behavior(cfg.behavior_name)
    if request.preset:
        _apply_preset(cfg, behavior_cls, request.preset)
    placed = {**request.top, "out_dir": request.out_dir} if request.out_dir else request.top
    apply_overrides(cfg, {k: v for k, v in placed.items() if v is not None})
    apply_overrides(cfg, request.overrides)
    notes: list[str] = []
    if request.resume and (note := check_resumed(started, cfg, Path(request.resume))):
        notes.append(note)
    _record_source(cfg, request)
    behavior = _build_behavior(cfg, behavior_cls)
    if fresh:  # values that scale with the run's length, unless given
        preset_keys = set(behavior_cls.about.presets[request.preset]) if request.preset else set()
        _scale_to_length(cfg, behavior, preset_keys | override_keys(request.overrides))
    finish_config(cfg, behavior)
    check_config(cfg)
    return ResolvedRun(cfg, behavior, notes)


def _check_request(request: RunRequest) -> None:
    """Stage 1: refuse options that exclude each other (one line each, naming them)."""
    sources = [
        name
        for name, given in (
            ("--resume", request.resume),
            ("--from", request.start_from),
            ("--config", request.config_file),
            ("a saved config", request.saved is not None),
            ("a baseline", request.baseline),
        )
        if given
    ]
    if request.resume and (request.preset or request.start_from):
        raise UsageError("--resume keeps the run's config; --preset and --from start new runs")
    if len(sources) > 1:
        raise UsageError(f"{' and '.join(sources)} exclude each other")
    if request.resume and request.out_dir:
        raise UsageError("--out and --resume exclude each other (a resumed run stays put)")
    if (request.config_file or request.saved is not None) and request.preset:
        raise UsageError("--config starts from a resolved config; --preset does not apply to it")


def _start(
    request: RunRequest, registry: PluginRegistry, read_checkpoint: CheckpointReader | None
) -> RunConfig:
    """Stage 2, where the config starts: a fresh run's defaults (the core's < the behaviour's
    ``train_defaults()``), the checkpoint's config (``start_from``), or a saved config (a run's
    ``config.json`` to resume, a ``config_file``, ``saved`` data, a ``baseline``'s empty one)
    read for its behaviour, which must be the requested one where one is. A saved run's config
    takes, for keys it lacks, the values it was trained with
    (:func:`~devlearn.config.run_config.from_dict`); a new run's file (``config_file``) a
    fresh run's values, the run-length defaults at its default length included; a baseline
    a fresh run's decision rate.

    Raises:
        UsageError: An unknown behaviour, a missing run folder, an unreadable config or
            checkpoint, or one that trains another behaviour.
    """
    data, source = request.saved, "the saved config"
    if request.resume:
        run_dir = Path(request.resume)
        if not run_dir.is_dir():
            raise UsageError(f"run directory {run_dir} does not exist")
        data, source = read_config_file(run_dir / CONFIG_FILE), f"run {run_dir}"
    elif request.config_file:
        data, source = read_config_file(request.config_file), request.config_file
    elif request.baseline:
        data = {}
    if request.start_from:
        if read_checkpoint is None:
            raise TypeError(
                "resolve_config: a request with start_from needs read_checkpoint "
                "(devlearn.training.checkpoint.checkpoint_config)"
            )
        cfg = read_checkpoint(str(request.start_from), registry, request.behavior)
    elif data is None:  # fresh
        behavior_cls = registry.behavior(request.behavior)
        cfg = new_config(behavior_cls)
        _apply_behavior_defaults(cfg, behavior_cls)
    else:
        name = data.get("behavior_name") or request.behavior
        if request.behavior and name != request.behavior:
            raise UsageError(f"{source} trains '{name}', not '{request.behavior}'")
        behavior_cls = registry.behavior(name)
        new = None  # a fresh run's config: what a new run's file lacks, a baseline's rate
        if request.config_file or request.baseline:
            new = new_config(behavior_cls)
            _apply_behavior_defaults(new, behavior_cls)
            _scale_to_length(new, _build_behavior(new, behavior_cls), set())
        cfg = from_dict(data, behavior_cls, new if request.config_file else None)
        if request.baseline and new is not None:
            cfg.env.action_repeat = new.env.action_repeat
    return cfg


def _apply_behavior_defaults(cfg: RunConfig, behavior_cls: type[Behavior]) -> None:
    """Apply the behaviour's ``about.train_defaults`` (read from its class: run settings are
    data) to a new run's ``cfg``."""
    apply_overrides(cfg, dict(behavior_cls.about.train_defaults))


def _apply_preset(cfg: RunConfig, behavior_cls: type[Behavior], preset: str) -> None:
    """Stage 3: apply the behaviour's preset ``preset`` (its ``presets``) and record its name
    in ``cfg.preset``.

    Raises:
        UsageError: The behaviour has no such preset (the valid ones are named).
    """
    presets = behavior_cls.about.presets
    if preset not in presets:
        raise UsageError(
            f"unknown preset '{preset}' for {behavior_cls.name}; "
            f"valid: {', '.join(presets) or 'none (it defines no presets)'}"
        )
    apply_overrides(cfg, presets[preset])
    cfg.preset = preset


def _record_source(cfg: RunConfig, request: RunRequest) -> None:
    """Stage 5 of a run from a checkpoint: it records the checkpoint and writes where
    ``--out`` says (not where the checkpoint's run wrote, whatever ``--set`` said)."""
    if request.start_from:
        cfg.out_dir = request.out_dir
        cfg.start_from = str(request.start_from)


def _build_behavior(cfg: RunConfig, behavior_cls: type[Behavior]) -> Behavior:
    """Stage 6: the behaviour a run of ``cfg`` trains, built on ``cfg.behavior`` (which it
    checks: the config's ``validate`` and its reward table).

    Raises:
        UsageError: The behaviour refuses its config (one line naming the behaviour).
    """
    try:
        return behavior_cls(cfg.behavior)
    except (ValueError, TypeError) as err:
        raise UsageError(f"{behavior_cls.name}: {err}") from None


def _scale_to_length(cfg: RunConfig, behavior: Behavior, keep: set[str]) -> None:
    """Stage 6 of a new run: apply ``behavior.about.run_length_defaults(cfg.total_steps)`` (values
    that scale with the run's length) to ``cfg``, except the keys in ``keep`` (what ``--set``
    or the preset gave). ``behavior`` is the one built on ``cfg.behavior``, so it sees the
    values."""
    scaled = behavior.about.length_defaults(int(cfg.total_steps))
    apply_overrides(cfg, {k: v for k, v in scaled.items() if k not in keep})


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
