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
attention over words, which the ROS node publishes.
"""

from __future__ import annotations

from torch import nn

from .baselines import TCNN, TUVFA
from .config import ModelConfig
from .trnet import TRNet


MODELS = {
    't-rnet-attn': lambda cfg: TRNet(cfg, attention=True),
    't-rnet': lambda cfg: TRNet(cfg, attention=False),
    't-cnn': TCNN,
    't-uvfa': TUVFA,
}


def build_model(name: str, cfg: ModelConfig) -> nn.Module:
    if name not in MODELS:
        raise ValueError(f'unknown model {name!r}; use one of {", ".join(MODELS)}')
    return MODELS[name](cfg)
