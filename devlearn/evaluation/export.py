"""Export a trained policy (observations to mean action) as ONNX or TorchScript."""

from __future__ import annotations

import contextlib
import io
import logging
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import torch
import torch.nn as nn

from devlearn.api.errors import UsageError
from devlearn.files import check_out_file, replaced_atomically, write_bytes_atomically

if TYPE_CHECKING:
    from devlearn.evaluation.scripted_policy import ObservationOrder
    from devlearn.plugins import PluginRegistry
    from devlearn.training.checkpoint import Checkpoint
    from devlearn.training.networks import MultiSenseModel

FORMATS = ("onnx", "torchscript")
"""Formats ``devlearn export`` writes."""
ACTION = "action"
"""Name of the exported graph's output."""


class DeterministicPolicy(nn.Module):
    """The policy at test time: the Gaussian's mean as the env applies it (paper: a_t = mu_t).

    ``forward(*observations)`` takes one tensor per observation, in :attr:`names` order, each
    (N, *shape) in the dtype the behaviour observes (uint8 images, float32 otherwise), and
    returns (N, action_dim) actions in [-1, 1]. Normalisers and the input scale are inside.

    Args:
        actor: A trained :class:`~devlearn.training.networks.MultiSenseModel` actor.
    """

    def __init__(self, actor: MultiSenseModel) -> None:
        super().__init__()
        self.actor = actor
        self.names = list(actor.obs_groups)
        self.eval()

    def forward(self, *observations: torch.Tensor) -> torch.Tensor:
        latent = self.actor.encode(dict(zip(self.names, observations)))
        return self.actor.distribution.deterministic_output(self.actor.mlp(latent))


def load_policy(
    behavior_name: str, checkpoint: str | Path, registry: PluginRegistry
) -> tuple[DeterministicPolicy, dict[str, np.ndarray]]:
    """Rebuild a checkpoint's deterministic policy and one observation of its behaviour.

    The behaviour's environment is built once (and reset) to learn the observations' names,
    shapes and dtypes.

    Returns:
        ``(policy, observation)``: observation name -> array of one step, unbatched.
    Raises:
        UsageError: Missing, corrupt or foreign checkpoint, or an environment that cannot be
            built from the checkpoint's config.
    """
    from devlearn.training.checkpoint import Checkpoint

    opened = Checkpoint.open(checkpoint, registry, behavior_name)
    actor, obs = actor_on_one_observation(opened)
    return DeterministicPolicy(actor), obs


def actor_on_one_observation(opened: Checkpoint) -> tuple[Any, dict[str, np.ndarray]]:
    """The checkpoint's policy network, built (and its weights checked: shapes, tensors, finite
    values) on one observation of its behaviour's environment, and that observation.

    Raises:
        UsageError: The weights do not fit, or the environment cannot be built.
    """
    from devlearn.env import BehaviorEnv

    try:
        env = BehaviorEnv(
            opened.behavior(), 0, training=False, action_repeat=opened.config.env.action_repeat
        )
    except OSError as exc:
        raise UsageError(
            f"cannot build the '{opened.behavior_name}' environment of checkpoint {opened.path} "
            f"(needed for its observation shapes): {exc}"
        ) from None
    try:
        obs = env.reset()
        return opened.actor(obs, env.action_dim), obs
    finally:
        env.close()


def example_inputs(
    policy: DeterministicPolicy | ObservationOrder, obs: dict[str, Any], batch: int = 4
) -> tuple[torch.Tensor, ...]:
    """``obs`` repeated into a batch, in the policy's input order: tensors (batch, *shape).

    More than one sample, so that the exporter keeps the batch axis dynamic (torch.export
    specialises axes of size 1).
    """
    return tuple(
        torch.from_numpy(np.repeat(np.array(obs[name])[None], batch, axis=0))
        for name in policy.names
    )


def export_policy(
    policy: DeterministicPolicy | ObservationOrder,
    obs: dict[str, Any],
    fmt: str,
    out: Path,
    extra_files: dict[str, str] | None = None,
) -> Path:
    """Write ``policy`` to ``out`` as ONNX (inputs named after the observations, batch axis
    dynamic, output ``action``) or TorchScript (``torch.jit.load(out)(*observations)``;
    ``extra_files`` stored beside it, name -> text, as a scripted policy's metadata).

    Raises:
        UsageError: Unknown format, missing ONNX packages, or an unwritable ``out`` (one that
            is not a regular file included, :func:`devlearn.files.check_out_file`).
    """
    if fmt not in FORMATS:
        raise UsageError(f"unknown export format '{fmt}'; valid: {', '.join(FORMATS)}")
    out = Path(out)
    check_out_file(out)
    inputs = example_inputs(policy, obs)
    try:  # written beside, then renamed: a failed write (a full disk) leaves no partial file
        if fmt == "torchscript":
            with torch.no_grad(), known_exporter_noise_silenced():
                traced = torch.jit.trace(policy, inputs, check_trace=False)
                # saved in memory, then written by Python: torch's own file writer aborts the
                # process on a full disk (issue #55), a Python write raises OSError
                buffer = io.BytesIO()
                torch.jit.save(traced, buffer, _extra_files=extra_files or {})
            write_bytes_atomically(out, buffer.getbuffer())
        else:
            with replaced_atomically(out) as partial:
                with torch.no_grad(), known_exporter_noise_silenced():
                    _export_onnx(policy, inputs, partial)
    except (OSError, RuntimeError) as exc:
        reason = getattr(exc, "strerror", None) or " ".join(str(exc).split())[:160]
        raise UsageError(f"cannot write {out}: {reason}") from None
    return out


HARMLESS_WARNINGS = (
    r".*isinstance\(treespec, LeafSpec\)` is deprecated",  # torch's own pytree use
    r"# The axis name: .* will not be used",  # one dynamic batch axis named for all inputs
    # torch 2.13 deprecates TorchScript (still written and read as before): the format of
    # devlearn export --format torchscript and of scripted policies, until they move
    r"`torch\.jit\.(trace|trace_method|save|load)` is deprecated",
)
"""Messages torch's exporters print on every successful export that say nothing about it."""
HARMLESS_LOGGERS = ("torch.onnx._internal.exporter._registration",)
"""Loggers whose warnings (torchvision's operators not registered: a policy uses none) are
hidden during an export; errors still show."""


@contextlib.contextmanager
def known_exporter_noise_silenced() -> Iterator[None]:
    """Within the block, the known harmless exporter warnings are hidden; any other shows."""
    loggers = [logging.getLogger(name) for name in HARMLESS_LOGGERS]
    levels = [logger.level for logger in loggers]
    with warnings.catch_warnings():
        for message in HARMLESS_WARNINGS:
            warnings.filterwarnings("ignore", message=message)
        for logger in loggers:
            logger.setLevel(logging.ERROR)
        try:
            yield
        finally:
            for logger, level in zip(loggers, levels):
                logger.setLevel(level)


def _export_onnx(
    policy: DeterministicPolicy | ObservationOrder, inputs: tuple[torch.Tensor, ...], out: Path
) -> None:
    try:
        import onnx  # noqa: F401
        import onnxscript  # noqa: F401
    except ImportError:
        raise UsageError(
            "ONNX export needs the onnx and onnxscript packages: pip install 'devlearn[export]'"
        ) from None
    with open(out, "wb"):  # fail early and clearly on an unwritable path
        pass
    batch = torch.export.Dim("batch", min=1)
    program = torch.onnx.export(
        policy,
        inputs,
        dynamo=True,
        input_names=policy.names,
        output_names=[ACTION],
        dynamic_shapes={"observations": tuple({0: batch} for _ in inputs)},
        verbose=False,
    )
    assert program is not None  # dynamo=True always returns the program
    program.save(str(out))
