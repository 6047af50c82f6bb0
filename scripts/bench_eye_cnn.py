"""Time hand regard's eye CNN: forward + backward per 64x64 image, fp32 against bf16 autocast
and channels-last memory, on one torch thread (what a one-core training run gets).

Usage (from the repository root, with the project set up): ``.venv/bin/python
scripts/bench_eye_cnn.py``. Prints milliseconds per image, best of three batches of 256.
"""

from __future__ import annotations

import time

import torch
from devlearn_hand_regard.encoders import EYE_FEATURES
from devlearn_hand_regard.eye_cnn import EyeCNN


def ms_per_image(net: torch.nn.Module, images: torch.Tensor, mode: str, repeats: int = 3) -> float:
    """Best-of-``repeats`` milliseconds of one image's forward and backward pass."""
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        if mode == "bf16":
            with torch.autocast("cpu", dtype=torch.bfloat16):
                loss = net(images).float().sum()
        elif mode == "channels_last":
            chw = images.permute(0, 3, 1, 2).contiguous(memory_format=torch.channels_last)
            loss = net.convs(chw).sum()
        else:
            loss = net(images).sum()
        loss.backward()
        best = min(best, time.perf_counter() - start)
    return 1e3 * best / len(images)


def main() -> None:
    torch.set_num_threads(1)
    torch.manual_seed(0)
    net, images = EyeCNN(EYE_FEATURES), torch.rand(256, 64, 64, 3)
    for mode in ("fp32", "bf16"):
        print(f"{mode}: {ms_per_image(net, images, mode):.3f} ms per image (forward + backward)")
    net = net.to(memory_format=torch.channels_last)
    print(f"channels_last: {ms_per_image(net, images, 'channels_last'):.3f} ms per image")


if __name__ == "__main__":
    main()
