"""Bit-for-bit recordings hold for one kind of CPU: torch's float kernels round differently on
another vector instruction set (an AVX-512 Xeon against the AVX2 machine the first recordings
came from: actions differ by ~1e-7, and an episode of contacts then diverges: self-touch seed 1
scored 0.69 on one and 0.59 on the other). A recording therefore names the CPU kind it was
made on; the reference recording (no kind in its name) is the one made first."""

from __future__ import annotations

from pathlib import Path


def cpu_kind() -> str:
    """``genuineintel-avx512``: the CPU's vendor and torch's vector instruction set."""
    import torch

    vendor = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("vendor_id"):
                vendor = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{vendor}-{torch.backends.cpu.get_cpu_capability()}".lower()


def for_this_cpu(path: Path) -> Path:
    """``path`` as recorded on this kind of CPU (``NAME.KIND.EXT``) when such a recording
    exists, else the reference recording ``path``."""
    own = path.with_name(f"{path.stem}.{cpu_kind()}{path.suffix}")
    return own if own.exists() else path


def to_record(path: Path) -> Path:
    """Where a recording made now goes: beside the reference, named for this kind of CPU (the
    reference itself when there is none yet)."""
    return path.with_name(f"{path.stem}.{cpu_kind()}{path.suffix}") if path.exists() else path
