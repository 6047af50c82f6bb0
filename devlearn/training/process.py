"""Process-wide settings of a training process: the distributed group, torch threads, console."""

from __future__ import annotations

import contextlib
import io
import os

import torch
import torch.distributed as dist


def init_distributed(device: str) -> None:
    """Join torchrun's process group once: gloo on the CPU, NCCL on cuda.

    On cuda the rank's GPU (``cuda:LOCAL_RANK``) is made current first, so that NCCL's
    barriers and object collectives use it rather than guessing from the global rank.
    """
    if int(os.getenv("WORLD_SIZE", "1")) > 1 and not dist.is_initialized():
        if torch.device(device).type == "cuda":
            torch.cuda.set_device(int(os.getenv("LOCAL_RANK", "0")))
            dist.init_process_group("nccl")
        else:
            dist.init_process_group("gloo")


@contextlib.contextmanager
def update_threads(threads: int):
    """Run the block with ``threads`` torch intra-op threads (0: unchanged), then restore."""
    before = torch.get_num_threads()
    if threads > 0 and threads != before:
        torch.set_num_threads(threads)
    try:
        yield
    finally:
        if torch.get_num_threads() != before:
            torch.set_num_threads(before)


@contextlib.contextmanager
def quiet():
    """Swallow rsl-rl's console report (the progress bar and metrics.jsonl replace it)."""
    with contextlib.redirect_stdout(io.StringIO()):
        yield
