# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""The relation MLP's nonlinearity: tanh in the form this package computes it."""

from __future__ import annotations

import torch


def sigmoid_tanh(x: torch.Tensor) -> torch.Tensor:
    """Return 2 sigmoid(2x) - 1, which is tanh(x) (see Tanh)."""
    return torch.sigmoid(x * 2).mul_(2).sub_(1)


class Tanh(torch.autograd.Function):
    """
    tanh, computed as 2 sigmoid(2x) - 1 (the same function).

    This torch's CPU tanh is 3 to 8x slower than its sigmoid (1.28 against 0.38 ms on 512k
    floats, one thread, AVX-512): the relation MLP's tanh was a tenth of a training step and
    a sixth of a new instruction's text code. The backward is tanh's own, from the output:
    grad * (1 - y^2).
    """

    @staticmethod
    def forward(ctx, x: torch.Tensor) -> torch.Tensor:
        y = sigmoid_tanh(x)
        ctx.save_for_backward(y)
        return y

    @staticmethod
    def backward(ctx, grad: torch.Tensor) -> torch.Tensor:
        (y,) = ctx.saved_tensors
        return torch.ops.aten.tanh_backward(grad, y)


def tanh(x: torch.Tensor) -> torch.Tensor:
    """Return the tanh of x as Tanh computes it, with no autograd call when none is needed."""
    return Tanh.apply(x) if x.requires_grad and torch.is_grad_enabled() else sigmoid_tanh(x)
