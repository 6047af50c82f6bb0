"""The paper's eye CNN computes exactly the paper's network: its outputs and gradients equal a
plain functional composition of the same layers (out-of-place ReLUs), bit for bit."""

from __future__ import annotations

import torch
import torch.nn.functional as F
from devlearn_hand_regard.eye_cnn import EyeCNN


def _reference(net: EyeCNN, images: torch.Tensor) -> torch.Tensor:
    convs = [m for m in net.convs if isinstance(m, torch.nn.Conv2d)]
    x = images.permute(0, 3, 1, 2)
    for conv in convs:
        x = F.relu(F.conv2d(x, conv.weight, conv.bias, conv.stride, conv.padding))
    return x.mean(dim=(2, 3))


def test_outputs_and_gradients_match_the_plain_network():
    torch.manual_seed(0)
    net = EyeCNN(16)
    images = torch.rand(4, 64, 64, 3)
    target = torch.randn(4, 16)

    out = net(images)
    ((out - target) ** 2).sum().backward()
    grads = [p.grad.clone() for p in net.parameters()]
    net.zero_grad()
    ref = _reference(net, images)
    ((ref - target) ** 2).sum().backward()

    assert out.shape == (4, 16)
    torch.testing.assert_close(out, ref, rtol=0, atol=1e-6)
    for got, want in zip(grads, (p.grad for p in net.parameters()), strict=True):
        torch.testing.assert_close(got, want, rtol=1e-5, atol=1e-6)
    # the ReLUs zero negative pre-activations: something is zeroed and the output is >= 0
    assert (out >= 0).all()


def test_inference_mode_matches_training_forward():
    torch.manual_seed(1)
    net = EyeCNN(8)
    images = torch.rand(3, 64, 64, 3)
    with torch.inference_mode():
        fast = net(images)
    torch.testing.assert_close(fast, net(images).detach(), rtol=0, atol=0)
