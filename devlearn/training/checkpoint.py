"""Checkpoints: atomic writes, safe (data-only) loading, clear errors for unusable files, and
:class:`Checkpoint`, an opened one (config, behaviour with its artifacts, policy network)."""

from __future__ import annotations

import contextlib
import errno
import io
import os
import pickle
import re
import shutil
import stat
import zipfile
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Self

import numpy as np
import torch

from devlearn.ages import check_age
from devlearn.api.errors import UsageError
from devlearn.config.checks import STEPS_MAX
from devlearn.config.run_config import from_dict, to_rsl_rl
from devlearn.files import TEMPORARY, replaced_atomically

if TYPE_CHECKING:
    from tensordict import TensorDict

    from devlearn.api.behavior import Behavior
    from devlearn.config.run_config import RunConfig
    from devlearn.plugins import PluginRegistry
    from devlearn.training.networks import MultiSenseModel

FORMAT = "devlearn-checkpoint-1"
"""Value of the ``format`` key every devlearn checkpoint holds."""
LATEST = "checkpoint_latest.pt"
"""Name of the newest checkpoint in a run directory."""
POLICY_KEYS = ("behavior", "config", "actor_state_dict")
"""Keys every checkpoint must hold (enough to rebuild and evaluate the policy)."""
RESUME_KEYS = (
    *POLICY_KEYS,
    "critic_state_dict",
    "optimizer_state_dict",
    "iteration",
    "env_steps",
    "curriculum",
    "env",
    "rng",
)
"""Keys a checkpoint must hold to resume training from it."""
_PERIODIC = re.compile(r"^checkpoint_(\d+)\.pt$")
_DTYPE_CLASSES = (
    "Bool Int8 Int16 Int32 Int64 UInt8 UInt16 UInt32 UInt64 Byte UByte Short UShort Int UInt Long "
    "ULong LongLong ULongLong Float16 Float32 Float64 LongDouble Complex64 Complex128 "
    "CLongDouble Bytes Str"
).split()


def allowed_globals() -> list[Any]:
    """The classes and functions (beyond torch's tensors, dicts, lists, tuples, numbers and
    strings) a checkpoint may name: numpy arrays of numbers, bools or strings, their dtypes and
    numpy scalars. None of them runs code of the file's choosing. docs/checkpoints.md."""
    from numpy._core import multiarray

    dtypes = [getattr(np.dtypes, f"{n}DType", None) for n in _DTYPE_CLASSES]
    dtypes = [d for d in dtypes if d is not None]
    return [multiarray._reconstruct, multiarray.scalar, np.ndarray, np.dtype, *dtypes]


def _global_names() -> set[str]:
    names = set()
    for obj in allowed_globals():
        for module in {obj.__module__, obj.__module__.replace("numpy._core", "numpy.core")}:
            names.add(f"{module}.{obj.__qualname__}")
    return names


def _write_error(path: Path, exc: OSError) -> UsageError:
    if exc.errno in (errno.ENOSPC, errno.EDQUOT):
        try:
            free = f"{shutil.disk_usage(path.parent).free / 2**20:.0f} MB free"
        except OSError:
            free = "no space"
        kept = sorted(p for p in path.parent.glob("checkpoint_*.pt") if p != path)
        if kept:
            advice = "the previous checkpoint is kept: free some space, then continue with --resume"
        else:
            advice = (
                "no checkpoint was written before it: free some space, then start the run "
                "again (--force replaces the folder)"
            )
        return UsageError(f"disk full: cannot write {path} ({free}); {advice}")
    return UsageError(f"cannot write {path}: {exc.strerror or exc}")


@contextlib.contextmanager
def _replaced_atomically(path: Path) -> Iterator[Path]:
    """devlearn's atomic writer (:func:`devlearn.files.replaced_atomically`) with a write error
    worded for a run's user (a full disk: what is kept and how to go on).

    Raises:
        UsageError: The file cannot be written (disk full, read-only, ...); ``path`` is unchanged.
    """
    try:
        with replaced_atomically(path) as tmp:
            yield tmp
    except OSError as exc:
        raise _write_error(path, exc) from None


def save_atomic(state: dict[str, Any], path: Path) -> None:
    """Write ``state`` with torch.save to ``path`` atomically (:func:`_replaced_atomically`),
    the bytes synced before the rename.

    Raises:
        UsageError: The file cannot be written (disk full, read-only, ...); ``path`` is unchanged.
    """
    path = Path(path)
    with _replaced_atomically(path) as tmp, open(tmp, "wb") as f:
        buffer = io.BytesIO()  # pickle in memory: a full disk is then a plain OSError
        torch.save(state, buffer)
        f.write(buffer.getbuffer())
        f.flush()
        os.fsync(f.fileno())


def link_atomic(source: Path, path: Path) -> None:
    """Make ``path`` a hard link to ``source`` atomically (a byte copy where links are
    unsupported; nothing is unpickled)."""
    with _replaced_atomically(Path(path)) as tmp:
        try:
            os.link(source, tmp)
        except OSError:
            with open(source, "rb") as src, open(tmp, "wb") as dst:
                shutil.copyfileobj(src, dst)
                dst.flush()
                os.fsync(dst.fileno())


def remove_temporaries(run_dir: Path) -> list[Path]:
    """Delete the temporaries of devlearn's atomic writer (``.checkpoint_64.pt.tmp-PID``,
    ``.config.json.tmp-PID``...) that killed runs left behind in their folder."""
    removed = []
    for p in Path(run_dir).glob(".*.tmp-*"):
        if TEMPORARY.match(p.name) and p.is_file():
            p.unlink(missing_ok=True)
            removed.append(p)
    return removed


_STRINGS = {
    "SHORT_BINUNICODE",
    "BINUNICODE",
    "BINUNICODE8",
    "UNICODE",
    "STRING",
    "BINSTRING",
    "SHORT_BINSTRING",
}


def _pickle_globals(path: Path, limit: int = 1 << 30) -> set[str]:
    """The ``module.name`` of every class or function the pickles in ``path`` would import,
    read from their opcodes (``pickletools``: nothing is executed). A legacy torch file is
    several pickles in a row; bytes that are not a pickle end the scan."""
    import pickletools
    from _compat_pickle import IMPORT_MAPPING, NAME_MAPPING

    names: set[str] = set()
    try:
        data = path.read_bytes()[:limit]
    except OSError:
        return names
    stream = io.BytesIO(data)
    while stream.tell() < len(data):
        start = stream.tell()
        memo: dict[int, Any] = {}
        recent: list[Any] = []  # values pushed lately (STACK_GLOBAL takes the last two)
        arg: Any  # an int for the memo opcodes (PUT, GET...), a str for the string ones
        try:
            for op, arg, _ in pickletools.genops(stream):
                if op.name == "GLOBAL":  # protocols 0-2: Python 2 names mapped as load does
                    module, _, name = str(arg).partition(" ")
                    module, name = NAME_MAPPING.get((module, name), (module, name))
                    names.add(f"{IMPORT_MAPPING.get(module, module)}.{name}")
                elif op.name in _STRINGS:
                    recent.append(arg)
                elif op.name == "MEMOIZE" and recent:
                    memo[len(memo)] = recent[-1]
                elif op.name in ("PUT", "BINPUT", "LONG_BINPUT") and recent:
                    memo[int(arg)] = recent[-1]
                elif op.name in ("GET", "BINGET", "LONG_BINGET"):
                    recent.append(memo.get(int(arg)))
                elif op.name == "STACK_GLOBAL" and len(recent) >= 2:
                    # a module or name built at load time (not a plain string) is named as such
                    module, name = (
                        v if isinstance(v, str) else "<computed at load time>" for v in recent[-2:]
                    )
                    names.add(f"{module}.{name}")
                elif op.name != "MEMOIZE":
                    recent.append(None)
        except Exception:
            break  # not (or no longer) a pickle
        if stream.tell() == start:
            break
    return names


def _torch_safe_globals() -> set[str]:
    """The names torch's weights-only loader allows in any file (tensors, storages, ordered
    dicts...), so that only foreign ones are reported."""
    try:
        from torch import _weights_only_unpickler

        return set(_weights_only_unpickler._get_allowed_globals())
    except Exception:  # a torch without it: report every name found
        return set()


def _refused(path: Path, names: list[str]) -> UsageError:
    return UsageError(
        f"checkpoint {path} refused: it needs {', '.join(names)}, which a devlearn checkpoint "
        "may not contain (only tensors, numbers, strings, lists, dicts and numpy arrays; "
        "docs/checkpoints.md); nothing in it was run"
    )


def not_a_file(path: Path) -> str:
    """Why ``path`` is not a regular file, in words: ``does not exist``, ``is a symbolic link
    loop``, ``is a folder``, ``is a FIFO (not a file)``..."""
    try:
        mode = path.stat().st_mode
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "is a symbolic link loop"
        if path.is_symlink():
            return f"is a symbolic link to a missing file ({os.readlink(path)})"
        return "does not exist"
    kinds = {
        stat.S_ISDIR: "a folder",
        stat.S_ISFIFO: "a FIFO",
        stat.S_ISSOCK: "a socket",
        stat.S_ISCHR: "a character device",
        stat.S_ISBLK: "a block device",
    }
    kind = next((name for test, name in kinds.items() if test(mode)), "not a regular file")
    return f"is {kind}, not a checkpoint file"


SCRIPTED_METADATA = "devlearn_policy.json"
"""The TorchScript extra file that makes an archive a scripted policy (another learner's policy,
:mod:`devlearn.evaluation.scripted_policy`), which only ``devlearn eval`` reads."""


def is_scripted_policy(path: str | Path) -> bool:
    """Whether ``path`` is a scripted policy file (a TorchScript archive holding
    :data:`SCRIPTED_METADATA`; a devlearn checkpoint, also a zip archive, holds none)."""
    path = Path(path)
    if not path.is_file() or not zipfile.is_zipfile(path):
        return False
    with zipfile.ZipFile(path) as archive:
        return any(name.endswith(f"/extra/{SCRIPTED_METADATA}") for name in archive.namelist())


def load_checkpoint(path: str | Path, required: tuple[str, ...] = POLICY_KEYS) -> dict[str, Any]:
    """Load a devlearn checkpoint (on the CPU) as data: ``torch.load(weights_only=True)`` with
    :func:`allowed_globals`; a file naming any other class or function is refused unrun.

    Args:
        path: The ``.pt`` file.
        required: Keys the checkpoint must hold (:data:`POLICY_KEYS`, :data:`RESUME_KEYS`).
    Raises:
        UsageError: The file is missing, truncated or unreadable, needs a type outside the
            allow-list (named), is not a devlearn checkpoint (a scripted policy is named as
            such) or lacks a required key.
    """
    path = Path(path)
    if not path.is_file():
        raise UsageError(f"checkpoint {path} {not_a_file(path)}")
    if is_scripted_policy(path):
        raise UsageError(
            f"{path} is a scripted policy (another learner's, docs/gymnasium.md): devlearn eval "
            "evaluates it; it holds no devlearn networks to slim, export or continue"
        )
    try:
        # A scan of the pickle's opcodes (nothing executed) names every foreign type at once.
        unsafe = set(torch.serialization.get_unsafe_globals_in_checkpoint(path))
    except Exception:
        # not a zip checkpoint (a plain or legacy torch pickle): scan its opcodes ourselves
        unsafe = _pickle_globals(path) - _torch_safe_globals()
    foreign = sorted(unsafe - _global_names())
    if foreign:
        raise _refused(path, foreign)
    try:
        with torch.serialization.safe_globals(allowed_globals()):
            state = torch.load(path, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError as exc:
        found = re.search(r"GLOBAL (\S+) was not|but got <class '([^']+)'>", str(exc))
        if found:
            raise _refused(path, [found.group(1) or found.group(2)]) from None
        raise UsageError(f"checkpoint {path} is corrupt or unreadable (UnpicklingError)") from None
    except Exception as exc:
        raise UsageError(
            f"checkpoint {path} is corrupt or unreadable ({type(exc).__name__})"
        ) from None
    if not isinstance(state, dict) or state.get("format") != FORMAT:
        raise UsageError(f"checkpoint {path} is not a devlearn checkpoint")
    missing = [k for k in required if k not in state]
    if missing:
        raise UsageError(
            f"checkpoint {path} is incomplete: it lacks {', '.join(missing)} "
            f"(a devlearn checkpoint holds {', '.join(required)})"
        )
    _check_shapes(state, path, required)
    return state


def _check_shapes(state: dict[str, Any], path: Path, required: tuple[str, ...]) -> None:
    expected = {
        "config": dict,
        "actor_state_dict": dict,
        "critic_state_dict": dict,
        "optimizer_state_dict": dict,
        "iteration": int,
        "env_steps": int,
        "curriculum": dict,
        "env": dict,
        "rng": dict,
    }
    for key in required:
        kind = expected.get(key)
        if kind is not None and not isinstance(state[key], kind):
            raise UsageError(
                f"checkpoint {path} is damaged: '{key}' is a {type(state[key]).__name__}, "
                f"expected a {kind.__name__}"
            )
    if "env" in required:
        ranks = state["env"].get("ranks")
        if not (
            isinstance(ranks, list)
            and ranks
            and isinstance(ranks[0], dict)
            and isinstance(ranks[0].get("envs"), list)
        ):
            raise UsageError(f"checkpoint {path} is damaged: 'env' lacks the envs' state")
    for key in ("iteration", "env_steps"):  # counts, wherever present (eval reads env_steps)
        if key not in state:
            continue
        if isinstance(state[key], bool) or not isinstance(state[key], int):
            raise UsageError(
                f"checkpoint {path} is damaged: '{key}' is {state[key]!r}, not a count"
            )
        if state[key] < 0:
            raise UsageError(f"checkpoint {path} is damaged: '{key}' is {state[key]}, below 0")
        if state[key] > STEPS_MAX:
            raise UsageError(
                f"checkpoint {path} is damaged: '{key}' is {state[key]:g}, above {STEPS_MAX:g}"
            )
    if "rng" in required:
        missing = [k for k in ("torch", "numpy", "random") if k not in state["rng"]]
        if missing:
            raise UsageError(f"checkpoint {path} is damaged: 'rng' lacks {', '.join(missing)}")
        _check_rng(state["rng"], path)


def _check_rng(rng: dict[str, Any], path: Path) -> None:
    """Raise UsageError unless each saved generator state loads into a fresh generator of its
    kind (so a resume cannot fail half-way through its restore)."""
    import random

    loaders = {
        "torch": lambda v: torch.Generator().set_state(v),
        "numpy": lambda v: np.random.RandomState().set_state(v),
        "random": lambda v: random.Random().setstate(v),
    }
    for name, load in loaders.items():
        try:
            load(rng[name])
        except Exception as exc:
            reason = " ".join(str(exc).split())[:120] or type(exc).__name__
            raise UsageError(
                f"checkpoint {path} is damaged: 'rng' holds an unusable {name} state ({reason})"
            ) from None


def state_dict_mismatch(expected: dict[str, Any], saved: Any) -> str | None:
    """What keeps ``saved`` (a checkpoint's network weights) from loading into a network whose
    ``state_dict()`` is ``expected``: the first missing, unexpected or mis-shaped entry (None
    when it fits)."""
    if not isinstance(saved, dict):
        return f"it holds a {type(saved).__name__}, not weights by name"
    missing = [k for k in expected if k not in saved]
    if missing:
        return f"it lacks '{missing[0]}' ({len(missing)} missing in all)"
    extra = [k for k in saved if k not in expected]
    if extra:
        return f"it holds '{extra[0]}', which the network has not ({len(extra)} unknown in all)"
    for key, value in expected.items():
        got = saved[key]
        if not isinstance(got, torch.Tensor):
            return f"'{key}' is a {type(got).__name__}, not a tensor"
        if tuple(got.shape) != tuple(value.shape):
            return f"'{key}' has shape {tuple(got.shape)}, the network expects {tuple(value.shape)}"
        if got.is_floating_point() and not bool(torch.isfinite(got).all()):
            return f"'{key}' holds NaN or infinite values"
    return None


def check_fits(expected: dict[str, Any], saved: Any, source: str, what: str) -> None:
    """Raise UsageError when ``what`` of a checkpoint (e.g. ``actor_state_dict``), named by
    ``source`` (``checkpoint PATH``), cannot load into a network whose ``state_dict()`` is
    ``expected`` (the one its behaviour builds under its config)."""
    reason = state_dict_mismatch(expected, saved)
    if reason:
        raise UsageError(
            f"{source} does not fit the network its behaviour builds under its config: "
            f"{what}: {reason}"
        )


def check_behavior(state: dict[str, Any], path: str | Path, behavior_name: str) -> None:
    """Raise UsageError unless the checkpoint was trained for ``behavior_name``."""
    if state["behavior"] != behavior_name:
        raise UsageError(
            f"checkpoint {path} was trained for '{state['behavior']}', not '{behavior_name}'"
        )


def periodic_checkpoints(run_dir: Path) -> list[Path]:
    """``checkpoint_<step>.pt`` files of a run, newest (highest step) first."""
    found = [
        (int(m.group(1)), p)
        for p in run_dir.glob("checkpoint_*.pt")
        if (m := _PERIODIC.match(p.name))
    ]
    return [p for _, p in sorted(found, reverse=True)]


def resume_checkpoint(
    run_dir: str | Path, skipped: list[str] | None = None
) -> tuple[Path, dict[str, Any]]:
    """Return the run's newest checkpoint that loads, by the env steps it holds:
    ``checkpoint_latest.pt`` unless a ``checkpoint_<step>.pt`` that loads is further along.

    Args:
        run_dir: The run folder.
        skipped: If given, receives one sentence per newer checkpoint that did not load and
            was passed over (so that a caller can say it resumes from an older one).
    Raises:
        UsageError: No directory, or no readable checkpoint in it (a run stopped before its
            first checkpoint is told to start again with --force; the unfinished temporary
            files such a run leaves are removed).
    """
    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise UsageError(f"run directory {run_dir} does not exist")
    periodic = periodic_checkpoints(run_dir)
    if not (run_dir / LATEST).exists() and not periodic:
        removed = remove_temporaries(run_dir)
        note = f" (removed {len(removed)} unfinished checkpoint file(s))" if removed else ""
        raise UsageError(
            f"no checkpoint in {run_dir}: the run stopped before its first checkpoint, so there "
            f"is nothing to resume{note}; start it again with --out {run_dir} --force"
        )
    errors = []
    best: tuple[Path, dict[str, Any]] | None = None
    if (run_dir / LATEST).exists():
        try:
            best = run_dir / LATEST, load_checkpoint(run_dir / LATEST, RESUME_KEYS)
        except UsageError as exc:
            errors.append(str(exc))
    for path in periodic:
        match = _PERIODIC.match(path.name)  # periodic_checkpoints() keeps only names it matches
        if best is not None and match and int(match.group(1)) <= best[1]["env_steps"]:
            break  # this and every older periodic checkpoint are no further along
        try:
            state = load_checkpoint(path, RESUME_KEYS)
        except UsageError as exc:
            errors.append(str(exc))
            continue
        if best is None or state["env_steps"] > best[1]["env_steps"]:
            best = path, state
        break
    if best is None:
        raise UsageError(f"no readable checkpoint in {run_dir}: {errors[0]}")
    if errors and skipped is not None:
        skipped += [
            f"{error}; resuming from {best[0].name} (step {best[1]['env_steps']:,}), the newest "
            "that loads"
            for error in errors
        ]
    return best


@dataclass
class SavedPolicy:
    """A policy file, opened: its state, the config it trained with and, built when asked for,
    its behaviour (with the policy artifacts it carries, e.g. hand regard's detector
    calibration). What a devlearn :class:`Checkpoint` and another learner's scripted policy
    (:class:`~devlearn.evaluation.scripted_policy.ScriptedPolicy`) share."""

    path: Path
    """The file."""
    state: dict[str, Any]
    """What it holds besides the weights' program: ``behavior``, ``config``, ``env_steps``..."""
    config: RunConfig
    """The run config it was trained with (keys an old config lacks take the values it was
    trained with, :func:`~devlearn.config.run_config.from_dict`)."""
    registry: PluginRegistry
    """The registry its behaviour is built from."""
    _behavior: Behavior | None = field(default=None, repr=False)

    @property
    def behavior_name(self) -> str:
        """The behaviour it was trained for."""
        return str(self.state["behavior"])

    @property
    def env_steps(self) -> int | None:
        """Physics steps it trained for, summed over its environments (devlearn's count: a
        decision of ``env.action_repeat`` K counts K; all ranks); None where the file does
        not say."""
        return int(self.state["env_steps"]) if "env_steps" in self.state else None

    @property
    def saved_config(self) -> dict[str, Any]:
        """Its config as the file saved it (:attr:`config` is that config completed)."""
        return dict(self.state["config"])

    def behavior(self) -> Behavior:
        """Its behaviour under its config, with the policy artifacts the file carries loaded
        (or found by name next to it, ``Behavior.load_policy_artifacts``); built once."""
        if self._behavior is None:
            self._behavior = behavior_with_artifacts(
                self.registry, self.config, self.state, self.path
            )
        return self._behavior


@dataclass
class Checkpoint(SavedPolicy):
    """An opened checkpoint (training checkpoint or policy file): its state, its config and,
    built when asked for, its behaviour (with the policy artifacts it carries, e.g. hand
    regard's detector calibration) and its policy network. Every command that reads a
    checkpoint opens it here (``devlearn eval``, ``export``, ``slim``, ``run --from``).

    Open with :meth:`open`.
    """

    @classmethod
    def open(
        cls,
        path: str | Path,
        registry: PluginRegistry,
        behavior_name: str = "",
        required: tuple[str, ...] = POLICY_KEYS,
    ) -> Self:
        """Load ``path`` (as data, :func:`load_checkpoint`) and rebuild its config.

        Args:
            path: The ``.pt`` file.
            registry: Plugin registry.
            behavior_name: The behaviour it must have been trained for (empty: any installed).
            required: Keys it must hold (:data:`POLICY_KEYS`; :data:`RESUME_KEYS` to resume).
        Raises:
            UsageError: Missing, corrupt, foreign or incomplete file, or trained for another
                (or no installed) behaviour.
        """
        path = Path(path)
        state = load_checkpoint(path, required)
        if behavior_name:
            check_behavior(state, path, behavior_name)
        config = from_dict(state["config"], registry.behavior(state["behavior"]))
        return cls(path, state, config, registry)

    @property
    def age_months(self) -> float | None:
        """The body's age it last trained at (a growing run's final age; None: the default
        body; a checkpoint from before ages: its config's)."""
        if "age_months" not in self.state:
            return self.config.infant.age_months
        if self.state["age_months"] is None:
            return None
        try:
            return check_age(self.state["age_months"], "its age_months")
        except ValueError as err:
            raise UsageError(f"checkpoint {self.path} is damaged: {err}") from None

    def actor(self, obs: dict[str, np.ndarray], action_dim: int) -> MultiSenseModel:
        """Its policy network (eval mode, CPU), built for one observation ``obs`` of its
        behaviour (name -> unbatched array) and ``action_dim`` actions.

        Raises:
            UsageError: The saved weights do not fit the network its config builds.
        """
        return load_actor(self.config, self.state, self.behavior(), obs, action_dim)


def checkpoint_config(path: str, registry: PluginRegistry, behavior: str) -> RunConfig:
    """The config the training checkpoint ``path`` was trained with, which must train
    ``behavior`` (empty: any installed): what ``devlearn run --from`` starts from
    (:class:`devlearn.config.resolve.CheckpointReader`, passed to ``resolve_config``).

    Raises:
        UsageError: A missing, corrupt or non-resumable checkpoint, or one of another behaviour.
    """
    return Checkpoint.open(path, registry, behavior, RESUME_KEYS).config


def behavior_with_artifacts(
    registry: PluginRegistry, config: RunConfig, state: dict[str, Any], path: Path
) -> Behavior:
    """The behaviour a policy file at ``path`` names (``state["behavior"]``: a checkpoint, a
    policy file, a scripted policy) under ``config``, with the policy artifacts it carries
    (``state["artifacts"]``) loaded, or found by name next to it
    (``Behavior.load_policy_artifacts``)."""
    behavior = registry.create(str(state["behavior"]), config.behavior)
    behavior.artifacts().load_policy_artifacts(dict(state.get("artifacts") or {}), path.parent)
    return behavior


def build_actor(
    cfg: RunConfig, behavior: Behavior, obs: dict[str, np.ndarray], action_dim: int
) -> MultiSenseModel:
    """The policy network ``cfg`` builds for ``behavior`` (freshly initialised, from torch's
    global generator): the network a run trains and :func:`load_actor` fills.

    Args:
        cfg: A run config.
        behavior: Its behaviour.
        obs: One observation (name -> unbatched array).
        action_dim: Number of actions.
    """
    from rsl_rl.utils import resolve_class, resolve_obs_groups

    from devlearn.training.process import quiet

    train_cfg = to_rsl_rl(cfg, behavior, list(obs))
    batch = observation_batch(obs)
    with quiet():  # rsl-rl prints the resolved sets
        groups = resolve_obs_groups(batch, train_cfg["obs_groups"], ["actor", "critic"])
    actor_class, actor_kwargs = resolve_class(train_cfg["actor"])
    actor: MultiSenseModel = actor_class(batch, groups, "actor", action_dim, **actor_kwargs)
    return actor


def load_actor(
    cfg: RunConfig,
    checkpoint: dict[str, Any],
    behavior: Behavior,
    obs: dict[str, np.ndarray],
    action_dim: int,
) -> MultiSenseModel:
    """Rebuild a checkpoint's policy network for ``behavior`` under ``cfg`` (eval mode, CPU).

    Args:
        cfg: The checkpoint's config.
        checkpoint: Its state (``actor_state_dict``).
        behavior: Its behaviour.
        obs: One observation (name -> unbatched array).
        action_dim: Number of actions.
    Raises:
        UsageError: The weights do not fit the network ``cfg`` builds.
    """
    actor = build_actor(cfg, behavior, obs, action_dim)
    source = f"the {behavior.name} checkpoint"
    check_fits(actor.state_dict(), checkpoint["actor_state_dict"], source, "actor_state_dict")
    actor.load_state_dict(checkpoint["actor_state_dict"])
    if actor.distribution is not None:  # the spread's ceiling where the checkpoint's run was
        steps = int(checkpoint.get("env_steps", 0) or 0)
        actor.distribution.set_progress(steps / max(int(cfg.total_steps), 1))
    return actor.eval()


def observation_batch(obs: dict[str, np.ndarray]) -> TensorDict:
    """One env's observations as a batch of one (copied): groups (1, *shape)."""
    from tensordict import TensorDict

    return TensorDict({k: torch.from_numpy(np.array(v)[None]) for k, v in obs.items()}, [1])
