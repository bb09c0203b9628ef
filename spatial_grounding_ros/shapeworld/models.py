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
for replacing the final convolution layer with a dense layer followed by a softmax"), on pixels:
- phi: a small CNN reduces the image, with two coordinate channels (CoordConv), to 8x8 cells of
  8 pixels (a stem over 4x4 patches, a 3x3 block and a 2x2 max-pool, a 3x3 block on the cells,
  a 1x1 convolution to `cell_dim` features, the paper's k). An object (10-14 pixels) covers a
  few cells; no two share one.
- The words h(l) (models.TextEncoder, layer-normalised) are attended once per role: the
  subject, the reference and the relation ("X is REL Y"). A role's score of word l is
  q_role^T h(l) plus a learned term in l's position (u in [-1, 1]) and |u|, started so that the
  subject attends to the first words, the reference to the last and the relation to the
  middle.
- r_ij = s(phi_i) + t(phi_j) + f(l_ij) over *every* pair of cells i != j: s and t score how
  well a cell fits the subject and the reference, with weights decoded from the attended
  subject and reference words (a k-vector and a bias each); f is the relation MLP (10, 10, 1,
  tanh, the paper's sizes) on the offset l_ij of j from i, its weights decoded from the
  relation words, as on grids (models.relation's split_params and relation_mlp). The r_ij are
  log-potentials: their sum is a soft "and" of the three.
- Z1[i] = log-mean-exp over j of r_ij (a soft max), and the head a log-mean-exp over the cells
  (a soft "some pair"), a linear layer to 2 logits and softmax.

Departures from the paper, each because the model otherwise stayed at chance (docs/shapeworld.md
has the runs): roles attended apart and started by position (with one attention for all, the
statement is symmetric in X and Y, and checking X and Y apart, the first thing to learn, gets no
gradient); the relation MLP sees the offset only, the cells' fit enters as the decoded s and t;
soft maxes instead of the paper's max and linear layer over Z1 flattened (a linear layer over
64 cells spreads the gradient over 60 empty ones).

t-VGG (Andreas et al. 2017, as the paper describes it, with L3's classifier): VGG-style
convolutions, each channel's maximum over the image, dense 512, 512 with tanh; the logit of
"true" is the dot product of that image representation with a vector decoded from the text
(L3's `ClsModel` scores an image by its representation's product with the description's
encoding). A scene head on the image representation, trained beside it (which shapes, colours
and pairs the image holds), stands in for the paper's ImageNet features: with a
concatenation, a flattened feature map or without the scene loss, t-VGG stayed at chance or
checked colours only (docs/shapeworld.md).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace
import math

import torch
from torch import nn

from .data import IMAGE, N_ATTRIBUTES
from ..models.encoders import TextEncoder
from ..models.relation import relation_mlp, split_params


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
    # then a max-pool of this side over the feature grid (1: none, 8x8 cells of 8 pixels)
    cell_pool: int = 1
    mlp: tuple = (10, 10)  # relation MLP hidden layers (output 1), tanh (the paper's)
    # t-VGG: stem and two blocks, 64 -> 4x4, then a max over the image per channel
    vgg_channels: tuple = (32, 64, 128)
    dense: tuple = (512, 512)  # t-VGG dense layers, tanh (the paper's)
    # t-VGG's own text encoder: word embedding and LSTM sizes (L3's: 128 and a 512 GRU)
    vgg_text: tuple = (64, 256)

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


def conv_blocks(channels: tuple, stem: int, inputs: int = 3) -> nn.Sequential:
    """
    Build a stem, then 3x3 convolution, batch norm, ReLU, 2x2 max-pool per further channel count.

    The stem embeds each stem x stem patch of pixels (a convolution with that stride, batch norm,
    ReLU): full-resolution 3x3 convolutions cost most of a step and add little on flat shapes.
    """
    layers = [nn.Conv2d(inputs, channels[0], stem, stride=stem, bias=False)]
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
        k, c = cfg.cell_dim, cfg.channels[-1]
        self.grid = IMAGE // cfg.stem // 2 ** (len(cfg.channels) - 1) // cfg.cell_pool  # 8
        # the image with two coordinate channels (CoordConv), so that a cell can tell where in
        # it its object lies; a 3x3 block on the cells, then a 1x1 convolution without ReLU
        self.phi = nn.Sequential(
            conv_blocks(cfg.channels, cfg.stem, 3 + 2),
            nn.Conv2d(c, c, 3, padding=1, bias=False),
            nn.BatchNorm2d(c),
            nn.ReLU(),
            nn.Conv2d(c, k, 1),
            nn.MaxPool2d(cfg.cell_pool),
        )
        axis = torch.linspace(-1, 1, IMAGE)
        self.register_buffer(
            'coords', torch.stack(torch.meshgrid(axis, axis, indexing='xy'))[None],
            persistent=False,
        )
        self.text = TextEncoder(cfg)
        self.word_norm = nn.LayerNorm(cfg.hidden)
        # attention over the words per role: subject, reference, relation; each role's score
        # of word l also has a term in its position u in [-1, 1] and |u|, started so that the
        # subject attends to the first words, the reference to the last, the relation to the
        # middle ("X is REL Y"): with the roles mixed, the statement is symmetric in X and Y,
        # and checking X and Y apart, the first thing to learn, would get no gradient
        self.query = nn.Linear(cfg.hidden, 3, bias=False)
        self.position = nn.Parameter(torch.tensor([[-4.0, 4.0, 0.0], [0.0, 0.0, -4.0]]))
        # decoded from the attended words: a k-vector per side (which cells match), and the
        # relation MLP on the pair's offset
        self.decode_subject = nn.Linear(cfg.hidden, k + 1)
        self.decode_reference = nn.Linear(cfg.hidden, k + 1)
        sizes = [2, *cfg.mlp, 1]
        self.layer_shapes = list(zip(sizes[1:], sizes[:-1]))
        self.decoder = nn.Linear(cfg.hidden, sum(o * i for o, i in self.layer_shapes))
        n, g = self.grid**2, self.grid
        # the (2g-1)^2 distinct offsets between cells, and which one each pair (i, j) has: the
        # relation MLP scores each offset once
        d = torch.arange(-(g - 1), g).float() / (g - 1)
        self.register_buffer(
            'offset_table', torch.stack(torch.meshgrid(d, d, indexing='xy'), -1).reshape(-1, 2),
            persistent=False,
        )
        rows, cols = torch.meshgrid(torch.arange(g), torch.arange(g), indexing='ij')
        rows, cols = rows.reshape(-1), cols.reshape(-1)
        d_row, d_col = rows[None, :] - rows[:, None] + g - 1, cols[None, :] - cols[:, None] + g - 1
        index = d_row * (2 * g - 1) + d_col
        self.register_buffer('offset_index', index, persistent=False)
        self.register_buffer('self_pair', torch.eye(n, dtype=torch.bool), persistent=False)
        self.classify = nn.Linear(1, 2)
        with torch.no_grad():
            self.classify.weight.copy_(torch.tensor([[-1.0], [1.0]]))
            self.classify.bias.zero_()

    def forward(self, images: torch.Tensor, tokens: torch.Tensor, return_aux: bool = False):
        b = len(images)
        x = torch.cat([images, self.coords.expand(b, -1, -1, -1)], 1)
        phi = self.phi(x).flatten(2).transpose(1, 2)  # (B, N, k)
        words, mask, _ = self.text(tokens)
        words = self.word_norm(words)
        length = mask.sum(1, keepdim=True).clamp(min=2) - 1
        u = (torch.arange(mask.shape[1])[None] / length * 2 - 1)[..., None]  # (B, L, 1)
        score = self.query(words) + u * self.position[0] + u.abs() * self.position[1]
        attention = score.masked_fill(~mask[..., None], float('-inf')).softmax(1)  # (B, L, 3)
        roles = torch.einsum('blr,blh->brh', attention, words)  # (B, 3, H)
        ws = self.decode_subject(roles[:, 0])
        wr = self.decode_reference(roles[:, 1])
        m_s = torch.einsum('bnd,bd->bn', phi, ws[:, :-1]) + ws[:, -1:]
        m_r = torch.einsum('bnd,bd->bn', phi, wr[:, :-1]) + wr[:, -1:]
        w = split_params(self.decoder(roles[:, 2]), self.layer_shapes)  # (B, out, in) per layer
        table = self.offset_table.expand(b, 1, -1, -1)  # (B, 1, (2g-1)^2, 2)
        rel = relation_mlp(w, table, None)[:, 0][:, self.offset_index]  # (B, N, N)
        r = m_s[:, :, None] + m_r[:, None, :] + rel
        # a soft max over pairs, as a log-mean-exp: at the scale of r whatever the grid
        n = r.shape[1]
        z1 = r.masked_fill(self.self_pair, float('-inf')).logsumexp(-1) - math.log(n - 1)
        logits = self.classify(z1.logsumexp(-1, keepdim=True) - math.log(n))
        if not return_aux:
            return logits
        return logits, {'relation_map': z1.view(b, self.grid, self.grid), 'attention': attention}


class ShapeWorldVGG(nn.Module):
    """t-VGG: conv net, max over the image, dense 512, 512 (tanh); dot product with the text."""

    def __init__(self, cfg: ShapeWorldConfig):
        super().__init__()
        self.cfg = cfg
        self.convs = conv_blocks(cfg.vgg_channels, cfg.stem)
        word_dim, hidden = cfg.vgg_text
        self.text = TextEncoder(replace(cfg, word_dim=word_dim, hidden=hidden))
        sizes = [cfg.vgg_channels[-1], *cfg.dense]
        layers = []
        for a, b in zip(sizes[:-1], sizes[1:]):
            layers += [nn.Linear(a, b), nn.Tanh()]
        self.dense = nn.Sequential(*layers)
        # L3's classifier (Andreas et al. 2017): the statement's encoding is the weight vector
        # of a linear classifier over the image's representation
        self.text_weights = nn.Linear(hidden, cfg.dense[-1])
        self.bias = nn.Parameter(torch.zeros(1))
        # which shapes, colours and pairs the image holds, read from its representation and
        # trained beside the statements (training.TrainConfig.scene_weight): our stand-in for
        # the ImageNet features the paper's t-VGG read
        self.scene = nn.Linear(cfg.dense[-1], N_ATTRIBUTES)

    def image(self, images: torch.Tensor) -> torch.Tensor:
        """(B, 3, 64, 64) -> (B, dense[-1]): each channel's strongest response anywhere."""
        return self.dense(self.convs(images).amax((2, 3)))

    def forward(self, images: torch.Tensor, tokens: torch.Tensor, return_aux: bool = False):
        _, _, text = self.text(tokens)
        image = self.image(images)
        score = (image * self.text_weights(text)).sum(1, keepdim=True) + self.bias
        logits = torch.cat([torch.zeros_like(score), score], 1)
        if not return_aux:
            return logits
        return logits, {'relation_map': None, 'attention': None, 'scene': self.scene(image)}


MODELS = {'t-rnet-attn': ShapeWorldTRNet, 't-vgg': ShapeWorldVGG}


def build_model(name: str, cfg: ShapeWorldConfig) -> nn.Module:
    if name not in MODELS:
        raise ValueError(f'ShapeWorld has no model {name!r}; use one of {", ".join(MODELS)}')
    return MODELS[name](cfg)
