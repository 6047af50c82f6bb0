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


REFERENCE_KIND: dict[str, str] = {
    # issue #39's median policies, recorded when they were published (the other four seeds'
    # policies left the tree in issue #56)
    "hand_regard__i39__paper.npz": "authenticamd-avx512",
    "hand_regard__i39__reach_t4.npz": "authenticamd-avx512",
    # issue #40's median CNN policy, recorded when it was published
    "hand_regard__i40__cnn.npz": "authenticamd-avx512",
    # issue #54's reruns with the new core learner, recorded when they were published
    "plugins__i54__hand_to_mouth__core_defaults.npz": "genuineintel-avx512",
    # issue #58's median both-hands policy, recorded when it was published
    "hand_regard__i58__both_hands.npz": "genuineintel-avx512",
}
"""The CPU kind a reference recording was made on, where it is known and not the AMD machine of
the first recordings: a machine of another kind has no recording to compare with."""


def recorded_elsewhere(path: Path) -> str | None:
    """Why ``path`` cannot be compared on this machine (its only recording was made on another
    kind of CPU, named), or None."""
    kind = REFERENCE_KIND.get(path.name)
    if for_this_cpu(path) == path and kind is not None and kind != cpu_kind():
        return (
            f"{path.name} was recorded on {kind} only; record it on this {cpu_kind()} machine "
            f"with the code it was published with: python tests/published_policies.py "
            f"{path.name.removesuffix('.npz')}"
        )
    return None
