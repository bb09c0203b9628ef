# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""The paper's baselines: t-CNN and t-UVFA."""

from __future__ import annotations

import torch
from torch import nn
import torch.nn.functional as F

from .config import head_code_size, ModelConfig
from .encoders import EntityEncoder, TextEncoder
from .head import build_head, outputs
from .protocol import Capabilities, EntityRows, KernelCode, TextVectorCode


class TCNN(EntityRows, nn.Module):
    """
    t-CNN (Janner et al. 2018 as in the paper's appendix).

    The text vector's first 3*3*k entries are a 3x3 kernel over the entity embeddings, giving Z1;
    the last 3 make Z2.
    """

    def __init__(self, cfg: ModelConfig):
        super().__init__()
        if cfg.far:
            raise ValueError("far relations are a relation network's; t-CNN has none")
        self.cfg = cfg
        self.phi = EntityEncoder(cfg)
        self.text = TextEncoder(cfg, cfg.skip_unknown)
        # a 3x3 kernel per embedding dimension, then the head's code: 66 for k = 7
        kernel = 9 * cfg.embed_dim
        self.decoder = nn.Linear(cfg.hidden, kernel + head_code_size(cfg.head, cfg.head_text))
        self.head = build_head(cfg)

    @staticmethod
    def supports() -> Capabilities:
        """Return what t-CNN supports: the entity table's extra rows, no attention, no far map."""
        return Capabilities(unseen_rows=True, distractor_rows=True)

    @property
    def capabilities(self) -> Capabilities:
        return self.supports()

    def forward(self, grids: torch.Tensor, tokens: torch.Tensor, return_aux: bool = False):
        return self.ground(grids, self.text_code(tokens), return_aux)

    def text_code(self, tokens: torch.Tensor) -> KernelCode:
        """All that an instruction contributes: the kernel (B, k, 3, 3) and the head's code."""
        vec = self.decoder(self.text(tokens)[2])
        kernels = vec[:, :9 * self.cfg.embed_dim].unflatten(1, (self.cfg.embed_dim, 3, 3))
        return KernelCode(kernels=kernels, head=vec[:, 9 * self.cfg.embed_dim:])

    def ground(self, grids: torch.Tensor, code: KernelCode, return_aux: bool = False):
        """Value maps of grids (B, H, W) for a text_code of B instructions (or of 1 for all)."""
        b, h, w = grids.shape
        k = self.cfg.embed_dim
        phi = self.phi(grids).permute(0, 3, 1, 2)  # (B, k, H+2, W+2)
        kernels = code.kernels.expand(b, -1, -1, -1).reshape(b, k, 3, 3)
        # one kernel per example: a grouped convolution over the batch
        z1 = F.conv2d(phi.reshape(1, b * k, h + 2, w + 2), kernels, groups=b).view(b, h, w)
        values = self.head(z1, code.head.expand(b, -1))
        return outputs(values, z1, None, return_aux)


class TUVFA(nn.Module):
    """
    t-UVFA.

    A text vector [7] concatenated with a convolutional state encoding at every cell, then
    deconvolution layers decode the value map.
    """

    def __init__(self, cfg: ModelConfig):
        super().__init__()
        c = cfg.uvfa_channels
        self.phi = nn.Embedding(cfg.n_entities, cfg.embed_dim)
        self.text = TextEncoder(cfg, cfg.skip_unknown)
        self.to_text = nn.Linear(cfg.hidden, cfg.uvfa_text)
        self.state = nn.Sequential(
            nn.Conv2d(cfg.embed_dim, c, 3, padding=1),
            nn.ReLU(),
            nn.Conv2d(c, c, 3, padding=1),
            nn.ReLU(),
        )
        self.deconv = nn.Sequential(
            nn.ConvTranspose2d(c + cfg.uvfa_text, c, 3, padding=1),
            nn.ReLU(),
            nn.ConvTranspose2d(c, 1, 3, padding=1),
        )

    @staticmethod
    def supports() -> Capabilities:
        """Return what t-UVFA supports: nothing beyond the kinds (its table has no extra rows)."""
        return Capabilities()

    @property
    def capabilities(self) -> Capabilities:
        return self.supports()

    def forward(self, grids: torch.Tensor, tokens: torch.Tensor, return_aux: bool = False):
        return self.ground(grids, self.text_code(tokens), return_aux)

    def text_code(self, tokens: torch.Tensor) -> TextVectorCode:
        """All that an instruction contributes: the text vector (B, 7)."""
        return TextVectorCode(text=self.to_text(self.text(tokens)[2]))

    def ground(self, grids: torch.Tensor, code: TextVectorCode, return_aux: bool = False):
        """Value maps of grids (B, H, W) for a text_code of B instructions (or of 1 for all)."""
        b, h, w = grids.shape
        state = self.state(self.phi(grids).permute(0, 3, 1, 2))
        text = code.text.expand(b, -1)[:, :, None, None].expand(-1, -1, h, w)
        values = self.deconv(torch.cat([state, text], 1)).squeeze(1)
        return outputs(values, torch.zeros_like(values), None, return_aux)
