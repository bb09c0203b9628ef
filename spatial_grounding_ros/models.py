# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Grounding models: t-RNetAttn (the paper's), t-RNet, t-CNN and t-UVFA, and a registry.

Every model maps (grids (B,H,W) long, tokens (B,L) long) to a value map (B,H,W), works on
any map size, and computes all cells, all cell pairs and all words of a batch at once.
`forward(..., return_aux=True)` also returns the relation map Z1 and (t-RNetAttn) the
attention over words, which the ROS node publishes.

Sizes are the paper's (section 3.2, appendix A); PuddleWorld numbers in comments.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

import torch
from torch import nn
import torch.nn.functional as F

from .text import PAD


def neighbour_offsets(radius: int) -> list[tuple[int, int]]:
    """
    Return the cells j around i, as (d_row, d_col).

    Radius 1 is the paper's 8 neighbours; the paper's footnote extends relations to cells further
    away (radius 2: 24 neighbours).
    """
    return [
        (dr, dc)
        for dr in range(-radius, radius + 1)
        for dc in range(-radius, radius + 1)
        if (dr, dc) != (0, 0)
    ]


def relative_positions(radius: int) -> torch.Tensor:
    """l_ij: a scalar code of j's position relative to i, evenly spaced in [-1, 1]."""
    return torch.linspace(-1.0, 1.0, len(neighbour_offsets(radius)))


@dataclass
class ModelConfig:
    """Hyper-parameters, all in one place (PuddleWorld values; ISI uses embed_dim 13)."""

    n_entities: int = 12  # entity kinds in the table (PuddleWorld: 12)
    vocab_size: int = 2  # words incl. <pad>, <unk>
    embed_dim: int = 7  # k: entity embedding (13 for ISI)
    word_dim: int = 15  # word embedding = LSTM input
    hidden: int = 30  # LSTM hidden size
    mlp: tuple = (10, 10)  # relation MLP hidden layers (output 1), tanh
    uvfa_text: int = 7  # t-UVFA text vector
    uvfa_channels: int = 16  # t-UVFA state encoder channels
    head: tuple = (8, 16, 32, 16, 8)  # output network: 3x3 conv channels before the last conv
    radius: int = 1  # relation neighbourhood (1: the paper's 8 neighbours)
    head_slope: float = 0.01  # negative slope of the head's ReLUs (0: plain ReLU)
    # G1, G2 rise by 1 every this many cells (0: span -1..1 whatever the size)
    gradient_cells: float = 0.0
    # entity kinds held out of training (the robustness study's unseen objects), see EntityEncoder
    unseen_kinds: int = 10

    # fields added after checkpoints were shipped, with the value those checkpoints had
    LATER_FIELDS = {'gradient_cells': 0.0, 'unseen_kinds': 0}

    def to_dict(self) -> dict:
        d = asdict(self)
        d['mlp'], d['head'] = list(self.mlp), list(self.head)
        return d

    @classmethod
    def from_dict(cls, d: dict) -> 'ModelConfig':
        d = {**cls.LATER_FIELDS, **d}
        missing = [f.name for f in fields(cls) if f.name not in d]
        if missing:
            raise ValueError(f'model config lacks {", ".join(missing)}')
        return cls(**{**d, 'mlp': tuple(d['mlp']), 'head': tuple(d['head'])})


def relation_param_count(cfg: ModelConfig) -> int:
    """
    Size of h: weights of f (no biases, as the paper counts) plus 3 gradient coefficients.

    (2k+1)*10 + 10*10 + 10*1 + 3 = 263 for k = 7, 383 for k = 13.
    """
    sizes = [2 * cfg.embed_dim + 1, *cfg.mlp, 1]
    return sum(a * b for a, b in zip(sizes[:-1], sizes[1:])) + 3


class TextEncoder(nn.Module):
    """Word embedding -> LSTM; per-word outputs h(k), the padding mask, and their mean."""

    def __init__(self, cfg: ModelConfig):
        super().__init__()
        self.embed = nn.Embedding(cfg.vocab_size, cfg.word_dim, padding_idx=PAD)
        self.lstm = nn.LSTM(cfg.word_dim, cfg.hidden, batch_first=True)

    def forward(self, tokens: torch.Tensor):
        mask = tokens != PAD
        mask[:, 0] = True  # an empty instruction still has one (unknown) word
        words, _ = self.lstm(self.embed(tokens))
        words = words * mask.unsqueeze(-1)
        mean = words.sum(1) / mask.sum(1, keepdim=True)
        return words, mask, mean


# Seed of the unseen kinds' embedding rows: the same rows in every model and every checkpoint.
UNSEEN_ROWS_SEED = 1010


def unseen_kind_ids(n_entities: int, count: int) -> list[int]:
    """Grid values of the first `count` unseen kinds: after the kinds and the off-map row."""
    return list(range(n_entities + 1, n_entities + 1 + count))


class EntityEncoder(nn.Module):
    """
    phi.

    An embedding per entity index, plus one learned 'off the map' entity that pads the border so
    edge cells have a full neighbourhood too.

    Rows n+1 .. n+U are `cfg.unseen_kinds` kinds that no training map holds (the robustness
    study's unseen objects, `unseen_kind_ids`): training never touches them (an embedding row
    that is never looked up gets no gradient, and Adam leaves it where it was), so they stay
    at nn.Embedding's own initial distribution, N(0, 1), drawn from a generator of their own
    (UNSEEN_ROWS_SEED). Their own generator keeps the global random stream, and with it the
    initialisation of everything else, as it was before these rows existed.
    """

    def __init__(self, cfg: ModelConfig, pad: int = 1):
        super().__init__()
        self.off_map, self.pad = cfg.n_entities, pad
        self.embed = nn.Embedding(cfg.n_entities + 1, cfg.embed_dim)
        unseen = torch.randn(
            cfg.unseen_kinds,
            cfg.embed_dim,
            generator=torch.Generator().manual_seed(UNSEEN_ROWS_SEED),
        )
        self.embed.weight = nn.Parameter(torch.cat([self.embed.weight.data, unseen]))
        self.embed.num_embeddings += cfg.unseen_kinds

    def with_unseen_rows(self, weight: torch.Tensor) -> torch.Tensor:
        """
        Complete a saved embedding `weight` that lacks some unseen rows with this encoder's.

        Checkpoints written before the unseen rows existed hold n+1 rows; they get the same
        deterministic rows a model trained with them has, so every checkpoint sees the same
        unseen objects.
        """
        return torch.cat([weight, self.embed.weight.data[len(weight):]])

    def forward(self, grids: torch.Tensor) -> torch.Tensor:
        """(B,H,W) -> (B,H+2p,W+2p,k) embeddings of the border-padded grid."""
        p = self.pad
        return self.embed(F.pad(grids, (p, p, p, p), value=self.off_map))


def neighbour_index(
    height: int, width: int, radius: int = 1, device=None
) -> tuple[torch.Tensor, torch.Tensor]:
    """
    Flat indices into the grid padded by `radius`.

    Each cell (H*W,) and its neighbours (H*W, n).
    """
    padded_w = width + 2 * radius
    rows, cols = torch.meshgrid(
        torch.arange(radius, height + radius, device=device),
        torch.arange(radius, width + radius, device=device),
        indexing='ij',
    )
    centre = (rows * padded_w + cols).reshape(-1)
    offsets = torch.tensor(
        [dr * padded_w + dc for dr, dc in neighbour_offsets(radius)], device=device
    )
    return centre, centre[:, None] + offsets[None, :]


def gradient_maps(height: int, width: int, device=None, cells: float = 0.0) -> torch.Tensor:
    """
    (3, H, W): G1 horizontal (west to east), G2 vertical (north to south), J ones.

    cells = 0: G1 and G2 span -1..1 whatever the map size (the paper's). cells > 0: they are
    0 at the centre and rise by 1 every `cells` cells, so one row further south is worth the
    same on any map; cells = 4.5 equals the paper's on 10x10 maps. With the span fixed, a
    row is worth 0.065 on 32x32 against 0.22 on 10x10, and "southernmost" picked a rock one
    or two rows short.
    """

    def ramp(n):
        if cells:
            return (torch.arange(n, dtype=torch.float32, device=device) - (n - 1) / 2) / cells
        return torch.linspace(-1, 1, n, device=device)

    g1 = ramp(width).expand(height, width)
    g2 = ramp(height)[:, None].expand(height, width)
    return torch.stack([g1, g2, torch.ones(height, width, device=device)])


class OutputHead(nn.Module):
    """
    tau: Z2 = b1*G1 + b2*G2 + b3*J, then 3x3 convolutions over [Z1; Z2] to the value map.

    `channels` = () is the single convolution of the paper's text; the default stack has the
    shape of the output network of Janner et al.'s code (SimpleConv: six 3x3 convolutions,
    3, 6, 12, 6, 3 channels), which produced the t-CNN numbers the paper compares against:
    its 11x11 receptive field lets a goal's value spread over a 10x10 map. We use it at
    8, 16, 32, 16, 8 channels: on PW local (t-RNet, 100 epochs) test MSE 0.249 -> 0.190 and
    PQ 0.881 -> 0.906, at +3 ms on a 128x128 map. No final ReLU: true values go negative (puddles,
    down to about -3.3), so a ReLU would clip those cells to 0, an error no training removes.
    """

    def __init__(self, channels: tuple = (), slope: float = 0.0, gradient_cells: float = 0.0):
        super().__init__()
        self.gradient_cells = gradient_cells
        sizes = [2, *channels, 1]
        self.convs = nn.ModuleList(
            nn.Conv2d(a, b, kernel_size=3, padding=1) for a, b in zip(sizes[:-1], sizes[1:])
        )
        # A leaky slope: with 3-channel layers, plain ReLUs sometimes all die early and the
        # map goes constant (PW global runs stuck at train MSE 1.5 while PW local learned).
        self.slope = slope

    def forward(self, z1: torch.Tensor, beta: torch.Tensor) -> torch.Tensor:
        b, h, w = z1.shape
        z2 = torch.einsum('bc,chw->bhw', beta, gradient_maps(h, w, z1.device, self.gradient_cells))
        x = torch.stack([z1, z2], dim=1)
        for n, conv in enumerate(self.convs):
            x = conv(x)
            if n < len(self.convs) - 1:
                x = F.leaky_relu(x, self.slope)
        return x.squeeze(1)


class TRNet(nn.Module):
    """
    Text-conditioned relation network.

    With attention (t-RNetAttn) the relation MLP's weights are decoded from h_ij = sum_k
    alpha_ij(k) h(k) for each cell pair; without it (t-RNet) from the mean of the LSTM outputs, the
    same for every pair.
    """

    def __init__(self, cfg: ModelConfig, attention: bool = True):
        super().__init__()
        self.cfg, self.attention = cfg, attention
        self.phi = EntityEncoder(cfg, pad=cfg.radius)
        self.text = TextEncoder(cfg)
        self.decoder = nn.Linear(cfg.hidden, relation_param_count(cfg))  # h -> 263
        if attention:
            # project h(k) to 2k dims to score it against [phi(s_i); phi(s_j)]. Zero at
            # start: uniform attention, which makes the model exactly t-RNet (the decoder is
            # linear), so training can begin with the cheap attention-free forward.
            self.attn = nn.Linear(cfg.hidden, 2 * cfg.embed_dim, bias=False)
            nn.init.zeros_(self.attn.weight)
        self.attention_on = attention  # training may switch it off while attn is still 0
        self.head = OutputHead(cfg.head, cfg.head_slope, cfg.gradient_cells)
        sizes = [2 * cfg.embed_dim + 1, *cfg.mlp, 1]
        self.layer_shapes = list(zip(sizes[1:], sizes[:-1]))  # (out, in) per layer

    def split_params(self, params: torch.Tensor) -> list[torch.Tensor]:
        """Cut a parameter vector (..., 263) into the relation MLP's weights (..., out, in)."""
        weights, start = [], 0
        for out, inp in self.layer_shapes:
            weights.append(params[..., start:start + out * inp].unflatten(-1, (out, inp)))
            start += out * inp
        return weights

    @staticmethod
    def relation_mlp(
        weights: list[torch.Tensor], x: torch.Tensor, attention: torch.Tensor | None
    ) -> torch.Tensor:
        """
        Compute r = W3 tanh(W2 tanh(W1 x)) over pairs x (B, N, 8, 2k+1).

        Without attention the weights are one set per map, (B, out, in). With attention the
        pair (i, j) uses W_ij = sum_k alpha_ij(k) W(k), the weights decoded from each word k
        (B, L, out, in); W_ij x = sum_k alpha_ij(k) (W(k) x), so each layer is one matmul per
        word and a weighted sum, never a weight matrix per pair (3x faster, same result).
        """
        for n, w in enumerate(weights):
            if attention is None:
                x = torch.einsum('bnpi,boi->bnpo', x, w)
            else:
                x = (attention.unsqueeze(-1) * torch.einsum('bnpi,bloi->bnplo', x, w)).sum(-2)
            if n < len(weights) - 1:
                x = torch.tanh(x)
        return x.squeeze(-1)

    def forward(self, grids: torch.Tensor, tokens: torch.Tensor, return_aux: bool = False):
        b, h, w = grids.shape
        k = self.cfg.embed_dim
        centre, nbrs = neighbour_index(h, w, self.cfg.radius, grids.device)
        n_nbrs = nbrs.shape[1]  # 8 at radius 1
        phi = self.phi(grids).flatten(1, 2)  # (B, (H+2)(W+2), k)
        phi_i = phi[:, centre]  # (B, N, k)
        phi_j = phi[:, nbrs]  # (B, N, 8, k)
        words, mask, mean = self.text(tokens)  # (B, L, 30), (B, L), (B, 30)
        word_params = self.decoder(words)  # (B, L, 263)
        attention = None
        if self.attention_on:
            # alpha_ij(k) ~ exp(h(k)^T A [phi_i; phi_j]); the score splits into an i part and
            # a j part, so it costs (B, N, L) + (B, N, 8, L), not a product over all three.
            q = self.attn(words)  # (B, L, 2k)
            score = torch.einsum('bnd,bld->bnl', phi_i, q[..., :k]).unsqueeze(2) + torch.einsum(
                'bnpd,bld->bnpl', phi_j, q[..., k:]
            )
            score = score.masked_fill(~mask[:, None, None, :], float('-inf'))
            attention = score.softmax(-1)  # (B, N, 8, L)
            # the decoder is linear and sum_k alpha = 1, so decoding h_ij equals the
            # alpha-weighted sum of the words' decoded parameters
            weights = self.split_params(word_params)  # (B, L, out, in) per layer
        else:
            weights = self.split_params(self.decoder(mean))  # (B, out, in) per layer
        rel = (
            relative_positions(self.cfg.radius).to(grids.device).expand(b, h * w, -1).unsqueeze(-1)
        )
        x = torch.cat([phi_i.unsqueeze(2).expand(-1, -1, n_nbrs, -1), phi_j, rel], -1)
        r = self.relation_mlp(weights, x, attention)  # (B, N, 8)
        z1 = r.max(dim=-1).values.view(b, h, w)
        beta = self.decoder(mean)[:, -3:]  # the last 3 entries of h
        values = self.head(z1, beta)
        if not return_aux:
            return values
        word_attention = None
        if attention is not None:  # how much each word mattered, averaged over all pairs
            word_attention = attention.mean(dim=(1, 2))
        return values, {'relation_map': z1, 'attention': word_attention}


class TCNN(nn.Module):
    """
    t-CNN (Janner et al. 2018 as in the paper's appendix).

    The text vector's first 3*3*k entries are a 3x3 kernel over the entity embeddings, giving Z1;
    the last 3 make Z2.
    """

    def __init__(self, cfg: ModelConfig):
        super().__init__()
        self.cfg = cfg
        self.phi = EntityEncoder(cfg)
        self.text = TextEncoder(cfg)
        self.decoder = nn.Linear(cfg.hidden, 9 * cfg.embed_dim + 3)  # 66 for k = 7
        self.head = OutputHead(cfg.head, cfg.head_slope, cfg.gradient_cells)

    def forward(self, grids: torch.Tensor, tokens: torch.Tensor, return_aux: bool = False):
        b, h, w = grids.shape
        k = self.cfg.embed_dim
        phi = self.phi(grids).permute(0, 3, 1, 2)  # (B, k, H+2, W+2)
        _, _, mean = self.text(tokens)
        vec = self.decoder(mean)
        kernels = vec[:, :-3].view(b, k, 3, 3)
        # one kernel per example: a grouped convolution over the batch
        z1 = F.conv2d(phi.reshape(1, b * k, h + 2, w + 2), kernels, groups=b).view(b, h, w)
        values = self.head(z1, vec[:, -3:])
        return (values, {'relation_map': z1, 'attention': None}) if return_aux else values


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
        self.text = TextEncoder(cfg)
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

    def forward(self, grids: torch.Tensor, tokens: torch.Tensor, return_aux: bool = False):
        b, h, w = grids.shape
        state = self.state(self.phi(grids).permute(0, 3, 1, 2))
        _, _, mean = self.text(tokens)
        text = self.to_text(mean)[:, :, None, None].expand(-1, -1, h, w)
        values = self.deconv(torch.cat([state, text], 1)).squeeze(1)
        aux = {'relation_map': torch.zeros_like(values), 'attention': None}
        return (values, aux) if return_aux else values


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
