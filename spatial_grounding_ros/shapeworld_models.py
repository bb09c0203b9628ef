# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
ShapeWorld classifiers: t-RNetAttn on pixels, and the t-VGG baseline.

Both map (images (B,3,64,64) float, tokens (B,L) long) to logits (B,2) over (false, true); the
softmax of the paper is in the cross-entropy loss. The text encoder is models.py's.

t-RNetAttn (paper section 3.2, appendix A "In ShapeWorld we use the same architectures ... except
for replacing the final convolution layer with a dense layer followed by a softmax"):
- phi: a small CNN reduces the image to a grid of cells: a stem embeds each 4x4 patch, a 3x3
  convolution block halves that to 8x8, a 1x1 convolution gives each cell `cell_dim` features
  (the paper's k), and a 2x2 max-pool keeps 4x4 cells of 16 pixels, about one object each. The
  receptive field stays local (16 pixels before the pool): with the four-block CNN of t-VGG
  (46 pixels) a cell sees most of the image, and the model memorised training images instead.
  The features are continuous, so the relation is computed on every pair's features (no table
  over entity kinds, as on grids).
- r_ij = f([phi_i; phi_j; l_ij]) over *every* pair of cells i != j, not the 8 neighbours: the
  objects a statement relates are anywhere in the image (the paper's footnote extends the
  neighbourhood this way). l_ij is j's offset from i, (d_col, d_row) / 3: over all pairs, one
  scalar code cannot tell left from right without a periodic function.
- f's weights are decoded from the words with attention, as on grids: alpha_ij(k) ~
  exp(h(k)^T A [phi_i; phi_j]).
- Z1[i] = max over j of r_ij, flattened, a linear layer to 2 logits.

t-VGG (Andreas et al. 2017, as the paper describes it): VGG-style convolutions, the image
features concatenated with the text vector (the mean LSTM output), dense 512, 512 with tanh,
then the 2-way output.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

import torch
from torch import nn

from .models import TextEncoder, TRNet
from .shapeworld import IMAGE


@dataclass
class ShapeWorldConfig:
    """Hyper-parameters of both models, all in one place."""

    vocab_size: int = 2  # words incl. <pad>, <unk>
    word_dim: int = 15  # word embedding = LSTM input (the paper's)
    hidden: int = 30  # LSTM hidden size (the paper's)
    # CNN: a stem over 4x4 patches (64 -> 16x16), then a 3x3 convolution + ReLU + 2x2
    # max-pool per further entry (16 -> 8x8)
    stem: int = 4
    channels: tuple = (32, 32)
    cell_dim: int = 16  # k: a cell's feature vector (PuddleWorld's entity embedding is 7)
    # then a max-pool of this side over the feature grid: 8x8 -> 4x4 cells of 16 pixels
    cell_pool: int = 2
    mlp: tuple = (10, 10)  # relation MLP hidden layers (output 1), tanh (the paper's)
    vgg_channels: tuple = (32, 32, 32)  # t-VGG: stem and two blocks, 64 -> 4x4
    dense: tuple = (512, 512)  # t-VGG dense layers, tanh (the paper's)

    def to_dict(self) -> dict:
        return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}

    @classmethod
    def from_dict(cls, d: dict) -> 'ShapeWorldConfig':
        names = {f.name for f in fields(cls)}
        if set(d) != names:
            raise ValueError(
                f'ShapeWorld model config fields {sorted(d)} are not {sorted(names)}'
            )
        return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in d.items()})


def conv_blocks(channels: tuple, stem: int) -> nn.Sequential:
    """
    Build a stem, then 3x3 convolution, batch norm, ReLU, 2x2 max-pool per further channel count.

    The stem embeds each stem x stem patch of pixels (a convolution with that stride, batch norm,
    ReLU): full-resolution 3x3 convolutions cost most of a step and add little on flat shapes.
    """
    layers = [nn.Conv2d(3, channels[0], stem, stride=stem, bias=False)]
    layers += [nn.BatchNorm2d(channels[0]), nn.ReLU()]
    previous = channels[0]
    for c in channels[1:]:
        layers += [
            nn.Conv2d(previous, c, 3, padding=1, bias=False),
            nn.BatchNorm2d(c),
            nn.ReLU(),
            nn.MaxPool2d(2),
        ]
        previous = c
    return nn.Sequential(*layers)


def pair_offsets(grid: int) -> torch.Tensor:
    """(N, N, 2) l_ij: (d_col, d_row) of cell j from cell i, over grid - 1 (so within [-1, 1])."""
    rows, cols = torch.meshgrid(torch.arange(grid), torch.arange(grid), indexing='ij')
    cells = torch.stack([cols.reshape(-1), rows.reshape(-1)], -1).float()
    return (cells[None, :, :] - cells[:, None, :]) / (grid - 1)


class ShapeWorldTRNet(nn.Module):
    """t-RNetAttn with a CNN observation encoder and a classification head."""

    def __init__(self, cfg: ShapeWorldConfig):
        super().__init__()
        self.cfg = cfg
        k = cfg.cell_dim
        self.grid = IMAGE // cfg.stem // 2 ** (len(cfg.channels) - 1) // cfg.cell_pool  # 4
        # a 1x1 convolution last, without ReLU, so cell features can be negative like embeddings
        self.phi = nn.Sequential(
            conv_blocks(cfg.channels, cfg.stem),
            nn.Conv2d(cfg.channels[-1], k, 1),
            nn.MaxPool2d(cfg.cell_pool),
        )
        self.text = TextEncoder(cfg)
        sizes = [2 * k + 2, *cfg.mlp, 1]  # input [phi_i; phi_j; d_col; d_row]
        self.layer_shapes = list(zip(sizes[1:], sizes[:-1]))  # (out, in) per layer
        # The relation MLP's weights are decoded from words normalised to unit scale, by a
        # decoder with no bias at start and fan-in-scaled weights, so that the statement, not
        # the decoder's bias, sets them from the first step: with the default init the LSTM's
        # outputs (std 0.1) moved the decoded weights by a seventh of their size between
        # statements, and the logits by 0.04.
        self.word_norm = nn.LayerNorm(cfg.hidden)
        self.decoder = nn.Linear(cfg.hidden, sum(o * i for o, i in self.layer_shapes))
        with torch.no_grad():
            self.decoder.bias.zero_()
            start = 0
            for out, inp in self.layer_shapes:
                rows = self.decoder.weight[start:start + out * inp]
                rows.normal_(0.0, 1.0 / (inp * cfg.hidden) ** 0.5)
                start += out * inp
        # zero at start: uniform attention over the words
        self.attn = nn.Linear(cfg.hidden, 2 * k, bias=False)
        nn.init.zeros_(self.attn.weight)
        n = self.grid**2
        self.register_buffer('offsets', pair_offsets(self.grid), persistent=False)
        self.register_buffer('self_pair', torch.eye(n, dtype=torch.bool), persistent=False)
        self.classify = nn.Linear(n, 2)  # Z1 flattened -> (false, true)
        # Start as "true by the mean of Z1": every cell's relation score then pushes the same
        # way, so the max pair of each cell learns what true statements share. From a random
        # head the cells' gradients cancel out, and every run sat at chance for epochs.
        with torch.no_grad():
            self.classify.weight.copy_(torch.tensor([-1.0, 1.0])[:, None].expand(2, n) / n)
            self.classify.bias.zero_()

    # decoded parameters (..., P) -> the relation MLP's weights (..., out, in), by layer_shapes
    split_params = TRNet.split_params

    def forward(self, images: torch.Tensor, tokens: torch.Tensor, return_aux: bool = False):
        b, k = len(images), self.cfg.cell_dim
        phi = self.phi(images).flatten(2).transpose(1, 2)  # (B, N, k), N = 64 cells
        words, mask, _ = self.text(tokens)  # (B, L, 30), (B, L)
        words = self.word_norm(words)
        # attention over words for every pair (i, j); the score splits into an i and a j part
        q = self.attn(words)  # (B, L, 2k)
        score = torch.einsum('bid,bld->bil', phi, q[..., :k])[:, :, None] + torch.einsum(
            'bjd,bld->bjl', phi, q[..., k:]
        )[:, None]  # (B, N, N, L)
        attention = score.masked_fill(~mask[:, None, None, :], float('-inf')).softmax(-1)
        w1, *rest = self.split_params(self.decoder(words))  # per word: (B, L, out, in)
        # First layer, per word then mixed by attention. It is linear in [phi_i; phi_j; l_ij], so
        # it splits into an i term, a j term and an offset term: N x N pairs never meet a
        # (2k+2)-wide weight, which makes this layer 3x cheaper than applying it to every pair.
        w_i, w_j, w_l = w1[..., :k], w1[..., k:2 * k], w1[..., 2 * k:]
        term_i = torch.einsum('bid,blod->bilo', phi, w_i)  # (B, N, L, out)
        term_j = torch.einsum('bjd,blod->bjlo', phi, w_j)
        first = (
            torch.einsum('bijl,bilo->bijo', attention, term_i)
            + torch.einsum('bijl,bjlo->bijo', attention, term_j)
            + torch.einsum('bijl,ijc,bloc->bijo', attention, self.offsets, w_l)
        )  # (B, N, N, out)
        # the remaining layers as on grids: tanh, then models.py's attention-mixed MLP
        r = TRNet.relation_mlp(rest, torch.tanh(first), attention)  # (B, N, N)
        z1 = r.masked_fill(self.self_pair, float('-inf')).max(-1).values  # (B, N)
        logits = self.classify(z1)
        if not return_aux:
            return logits
        relation_map = z1.view(b, self.grid, self.grid)
        return logits, {'relation_map': relation_map, 'attention': attention.mean(dim=(1, 2))}


class ShapeWorldVGG(nn.Module):
    """t-VGG: conv net, [image features; text vector] -> dense 512, 512 (tanh) -> 2."""

    def __init__(self, cfg: ShapeWorldConfig):
        super().__init__()
        self.cfg = cfg
        self.convs = conv_blocks(cfg.vgg_channels, cfg.stem)
        self.text = TextEncoder(cfg)
        # the text vector is 30 numbers of about 0.1 beside 512 image features of about 1:
        # normalised, it is not drowned out at the start
        self.text_norm = nn.LayerNorm(cfg.hidden)
        side = IMAGE // cfg.stem // 2 ** (len(cfg.vgg_channels) - 1)
        sizes = [cfg.vgg_channels[-1] * side * side + cfg.hidden, *cfg.dense]
        layers = []
        for a, b in zip(sizes[:-1], sizes[1:]):
            layers += [nn.Linear(a, b), nn.Tanh()]
        self.dense = nn.Sequential(*layers, nn.Linear(sizes[-1], 2))

    def forward(self, images: torch.Tensor, tokens: torch.Tensor, return_aux: bool = False):
        _, _, text = self.text(tokens)
        logits = self.dense(torch.cat([self.convs(images).flatten(1), self.text_norm(text)], 1))
        return (logits, {'relation_map': None, 'attention': None}) if return_aux else logits


MODELS = {'t-rnet-attn': ShapeWorldTRNet, 't-vgg': ShapeWorldVGG}


def build_model(name: str, cfg: ShapeWorldConfig) -> nn.Module:
    if name not in MODELS:
        raise ValueError(f'ShapeWorld has no model {name!r}; use one of {", ".join(MODELS)}')
    return MODELS[name](cfg)
