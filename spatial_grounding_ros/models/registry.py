# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Every grid model by name: t-RNetAttn, t-RNet, t-CNN, t-UVFA.

Every model maps (grids (B,H,W) long, tokens (B,L) long) to a value map (B,H,W), works on
any map size, and computes all cells, all cell pairs and all words of a batch at once.
`forward(..., return_aux=True)` also returns the relation map Z1 and (t-RNetAttn) the
attention over words, which the ROS node publishes. What each supports (protocol.Capabilities)
is its class's to declare; `capabilities` asks it by name, before a model is built.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from torch import nn

from .baselines import TCNN, TUVFA
from .config import ModelConfig
from .protocol import Capabilities
from .trnet import TRNet


@dataclass(frozen=True)
class ModelKind:
    """A model class and the options it is built with."""

    cls: type
    options: dict = field(default_factory=dict)

    def __call__(self, cfg: ModelConfig) -> nn.Module:
        return self.cls(cfg, **self.options)

    @property
    def capabilities(self) -> Capabilities:
        return self.cls.supports(**self.options)


MODELS = {
    't-rnet-attn': ModelKind(TRNet, {'attention': True}),
    't-rnet': ModelKind(TRNet, {'attention': False}),
    't-cnn': ModelKind(TCNN),
    't-uvfa': ModelKind(TUVFA),
}


def model_kind(name: str) -> ModelKind:
    """Return the registered model `name`, or raise ValueError listing the names."""
    if name not in MODELS:
        raise ValueError(f'unknown model {name!r}; use one of {", ".join(MODELS)}')
    return MODELS[name]


def build_model(name: str, cfg: ModelConfig) -> nn.Module:
    return model_kind(name)(cfg)


def capabilities(name: str) -> Capabilities:
    """Return what the model `name` supports, as its class declares it."""
    return model_kind(name).capabilities
