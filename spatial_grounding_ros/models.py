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
import functools

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
    axial: bool = False  # the head's second layer also reads map-wide row/column maxima
    # a second relation map: each cell against every cell within FAR_REACH, its score the
    # relation MLP's at a 'far' position code minus a learned cost per squared cell of
    # distance ("the tree closest to the star")
    far: bool = False
    # the instruction scales and shifts the head's first-layer channels (FiLM): the output
    # network knows which geometry the instruction asks for
    head_text: bool = False
    # entity kinds held out of training (the robustness study's unseen objects), see EntityEncoder
    unseen_kinds: int = 10
    # kinds after those whose embeddings training redraws at every step: its distractor objects
    # (TrainConfig.distractors), so a model learns to pass over things it does not know
    distractor_kinds: int = 0

    # fields added after checkpoints were shipped, with the value those checkpoints had
    LATER_FIELDS = {
        'gradient_cells': 0.0,
        'axial': False,
        'unseen_kinds': 0,
        'head_text': False,
        'far': False,
        'distractor_kinds': 0,
    }

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


def head_code_size(channels: tuple, film: bool) -> int:
    """
    Return the size of what the instruction gives an output network of `channels`.

    3 gradient coefficients, and with `film` a scale and a shift per first-layer channel.
    """
    return 3 + (2 * channels[0] if film and channels else 0)


def relation_param_count(cfg: ModelConfig) -> int:
    """
    Size of h: weights of f (no biases, as the paper counts) plus the head's code.

    (2k+1)*10 + 10*10 + 10*1 + 3 = 263 for k = 7, 383 for k = 13 (without head_text).
    """
    sizes = [2 * cfg.embed_dim + 1, *cfg.mlp, 1]
    weights = sum(a * b for a, b in zip(sizes[:-1], sizes[1:]))
    return weights + head_code_size(cfg.head, cfg.head_text)


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


def distractor_kind_ids(cfg: ModelConfig) -> list[int]:
    """Grid values of the distractor kinds: after the unseen ones, never one of theirs."""
    first = cfg.n_entities + 1 + cfg.unseen_kinds
    return list(range(first, first + cfg.distractor_kinds))


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
    initialisation of everything else, as it was before these rows existed. The
    `cfg.distractor_kinds` rows after them are training's distractors, redrawn from the same
    N(0, 1) at every step (augment.add_distractors): other draws than the unseen rows'.
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
        distractors = torch.zeros(cfg.distractor_kinds, cfg.embed_dim)  # redrawn each step
        self.embed.weight = nn.Parameter(torch.cat([self.embed.weight.data, unseen, distractors]))
        self.embed.num_embeddings += cfg.unseen_kinds + cfg.distractor_kinds

    def with_unseen_rows(self, weight: torch.Tensor) -> torch.Tensor:
        """
        Complete a saved embedding `weight` that lacks some unseen rows with this encoder's.

        Checkpoints written before the unseen rows existed hold n+1 rows; they get the same
        deterministic rows a model trained with them has, so every checkpoint sees the same
        unseen objects.
        """
        return torch.cat([weight, self.embed.weight.data[len(weight):]])

    def pad_grid(self, grids: torch.Tensor) -> torch.Tensor:
        """(B,H,W) -> (B,H+2p,W+2p) entity indices, the border off the map."""
        p = self.pad
        return F.pad(grids, (p, p, p, p), value=self.off_map)

    def forward(self, grids: torch.Tensor) -> torch.Tensor:
        """(B,H,W) -> (B,H+2p,W+2p,k) embeddings of the border-padded grid."""
        return self.embed(self.pad_grid(grids))


def shifted(padded: torch.Tensor, radius: int) -> list[torch.Tensor]:
    """
    Each cell's neighbour at every offset, in neighbour_offsets order.

    (B, H+2r, W+2r, ...) padded by `radius` -> one (B, H, W, ...) view per offset: the work is
    per offset, never per cell.
    """
    height, width = padded.shape[1] - 2 * radius, padded.shape[2] - 2 * radius
    return [
        padded[:, radius + dr:radius + dr + height, radius + dc:radius + dc + width]
        for dr, dc in neighbour_offsets(radius)
    ]


def present_kinds(grids: torch.Tensor, n_entities: int) -> torch.Tensor:
    """Return the entity kinds in `grids`, ascending (a count, not a sort: cheap on big maps)."""
    return torch.bincount(grids.flatten(), minlength=n_entities).nonzero().flatten()


def kinds_per_map(grids: torch.Tensor, n_kinds: int, off_map: int) -> torch.Tensor:
    """
    Return each map's kinds (B, K), ascending, K the most any map of `grids` (B, H, W) holds.

    A map with fewer is padded with kinds it does not hold (never `off_map`, the neighbour
    kind past the border): their table rows are scored and never read. `n_kinds`: the
    entity table's rows, unseen and distractor kinds included.
    """
    b = grids.shape[0]
    held = torch.zeros(b, n_kinds, dtype=torch.int8, device=grids.device)
    held.scatter_(1, grids.flatten(1), 1)
    held[:, off_map] = -1  # last in the order below: never a padding kind
    count = int(held.eq(1).sum(1).max())
    # held kinds first, then the absent ones, each ascending (a stable sort)
    return held.argsort(dim=1, descending=True, stable=True)[:, :count]


def outputs(values: torch.Tensor, z1: torch.Tensor, attention, return_aux: bool):
    """Return a model's output: the value map, and with return_aux Z1 and the attention."""
    return (values, {'relation_map': z1, 'attention': attention}) if return_aux else values


@functools.lru_cache(maxsize=16)
def gradient_maps(height: int, width: int, device=None, cells: float = 0.0) -> torch.Tensor:
    """
    (3, H, W): G1 horizontal (west to east), G2 vertical (north to south), J ones (read only).

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

    `axial`: the second layer also reads AxialViews of the first layer's channels, so the
    head can compare what lies anywhere along a row or column, not only within 6 cells.
    `film`: the code's entries after beta scale and shift the first layer's channels.
    `inputs`: 3 when t-RNet's far relation map joins Z1 and Z2.
    """

    def __init__(
        self,
        channels: tuple = (),
        slope: float = 0.0,
        gradient_cells: float = 0.0,
        axial: bool = False,
        film: bool = False,
        inputs: int = 2,
    ):
        super().__init__()
        self.gradient_cells = gradient_cells
        self.axial, self.film = axial and len(channels) > 0, film and len(channels) > 0
        self.inputs = inputs  # Z1, Z2 and, with t-RNet's far relation, its map
        # entries of the instruction's code this head reads: beta, then the FiLM's
        self.code_size = head_code_size(channels, film)
        sizes = [inputs, *channels, 1]
        # with axial views the second layer also reads AXIAL_VIEWS maps per channel of the first
        self.convs = nn.ModuleList(
            nn.Conv2d(a * (1 + AXIAL_VIEWS if self.axial and n == 1 else 1), b, 3, padding=1)
            for n, (a, b) in enumerate(zip(sizes[:-1], sizes[1:]))
        )
        # A leaky slope: with 3-channel layers, plain ReLUs sometimes all die early and the
        # map goes constant (PW global runs stuck at train MSE 1.5 while PW local learned).
        self.slope = slope
        # maps of more than tile x tile cells run in tiles of that side (memory: see forward)
        self.tile = 256

    def forward(
        self, z1: torch.Tensor, code: torch.Tensor, far: torch.Tensor | None = None, layout=None
    ) -> torch.Tensor:
        """
        Value maps (B, H, W) from Z1 (B, H, W) and the instruction's code (B, code_size).

        `far`: t-RNet's far relation map (B, H, W), a third input map. `layout`: a
        torch.memory_format, or None to choose (convolve).
        """
        h, w = z1.shape[1:]
        beta, film = code[:, :3], code[:, 3:] if self.film else None
        gradients = gradient_maps(h, w, z1.device, self.gradient_cells).view(3, h * w)
        z2 = (beta @ gradients).view(-1, h, w)
        x = torch.stack([z1, z2] if far is None else [z1, z2, far], dim=1)
        if not (self.axial or self.film):
            return self.tiled(x, first=0, layout=layout)
        # the views are map-wide: the first layer runs on the whole map (8 channels a cell)
        x = self.convolve(x, first=0, last=1, film=film, layout=layout)
        views = {1: [AxialViews(x)]} if self.axial else None
        return self.tiled(x, first=1, views=views, layout=layout)

    def tiled(
        self,
        x: torch.Tensor,
        first: int,
        last: int | None = None,
        views: dict | None = None,
        layout=None,
    ) -> torch.Tensor:
        """Run layers first..last-1 on x (B, C, H, W), in tiles when the map is large."""
        last = len(self.convs) if last is None else last
        b, _, h, w = x.shape
        if h * w <= self.tile * self.tile:
            return self.convolve(x, first, last, views, window=(0, h, 0, w), layout=layout)
        # Large maps go through in tiles, so the 8..32-channel activations exist for one tile
        # at a time. Each 3x3 convolution reaches one cell further, so a tile read with a halo
        # of one cell per layer has exact values everywhere inside it: the zero padding at the
        # halo's cut edges only reaches into the halo. At the map's own edges the tile is cut
        # where the map ends, so the padding there is the untiled padding.
        halo, t = last - first, self.tile
        out = None
        for top in range(0, h, t):
            for left in range(0, w, t):
                bottom, right = min(top + t, h), min(left + t, w)
                r0, c0 = max(top - halo, 0), max(left - halo, 0)
                r1, c1 = min(bottom + halo, h), min(right + halo, w)
                window = (r0, r1, c0, c1)
                tile = self.convolve(
                    x[:, :, r0:r1, c0:c1], first, last, views, window=window, layout=layout
                )
                if out is None:  # (B, H, W) values, or (B, C, H, W) activations
                    out = tile.new_empty(*tile.shape[:-2], h, w)
                out[..., top:bottom, left:right] = tile[
                    ..., top - r0:bottom - r0, left - c0:right - c0
                ]
        return out

    def convolve(
        self,
        x: torch.Tensor,
        first: int = 0,
        last: int | None = None,
        views: dict | None = None,
        window: tuple[int, int, int, int] | None = None,
        film: torch.Tensor | None = None,
        layout=None,
    ) -> torch.Tensor:
        """
        Run layers first..last-1 on x (B, C, H, W).

        Through the last layer: (B, H, W) values; else the activations. `views`
        ({layer: [views]}) of the whole map join that layer's input, cut to `window` (top,
        bottom, left, right) of x. `film` (B, 2C): the first layer's scale and shift.
        """
        last = len(self.convs) if last is None else last
        if layout is None:
            # channels-last is oneDNN's fast layout on CPU for batches and large maps (one
            # thread: 2.3x on a 512x512 map, 1.6x on a training batch of 24x24 maps); one map
            # of up to 96x96 runs faster in the plain layout. The bench times both.
            big = x.shape[0] > 1 or x.shape[2] * x.shape[3] > 96 * 96
            layout = torch.channels_last if big else torch.contiguous_format
        x = x.contiguous(memory_format=layout)
        for n in range(first, last):
            if views and views.get(n):
                x = torch.cat([x, *(v.window(*window) for v in views[n])], 1)
            x = self.convs[n](x)
            if n == 0 and film is not None:
                scale, shift = film[..., None, None].chunk(2, dim=1)
                x = x * (1 + scale) + shift
            if n < len(self.convs) - 1:
                x = F.leaky_relu(x, self.slope, inplace=True)  # the conv's own output
        return x[:, 0] if last == len(self.convs) else x


class AxialViews:
    """
    Map-wide views of each channel of x (B, C, H, W), cut to any window as (B, 6C, h, w).

    Per channel and cell: the maxima of the cell's row and of its column, and of all cells
    strictly west, east, north and south of its column or row. A 3x3 stack sees 13x13 cells;
    these let it answer "westernmost rock" (a rock with no rock in a column to its west), "row of
    the tree and column of the house" and "two below the northernmost house" on a map of any
    size, at O(HW) cost. Where no cell lies beyond (the first column, ...), the channel's
    map-wide minimum stands in, so values stay in range. Only the profiles along one row and
    one column are kept, so tiles of a large map share them.
    """

    def __init__(self, x: torch.Tensor):
        low = x.amin(dim=(2, 3))[..., None]  # (B, C, 1)
        cols, rows = x.amax(dim=2), x.amax(dim=3)  # (B, C, W), (B, C, H)

        def beyond(profile: torch.Tensor) -> torch.Tensor:
            """Max over the entries before each one along the last axis (exclusive prefix max)."""
            return torch.cat([low, profile.cummax(-1).values[..., :-1]], -1)

        # constant along a column (varies with the column) / along a row
        self.by_column = torch.stack([cols, beyond(cols), beyond(cols.flip(-1)).flip(-1)], 1)
        self.by_row = torch.stack([rows, beyond(rows), beyond(rows.flip(-1)).flip(-1)], 1)

    def window(self, top: int, bottom: int, left: int, right: int) -> torch.Tensor:
        row = self.by_row[..., top:bottom, None].expand(-1, -1, -1, -1, right - left)
        column = self.by_column[..., None, left:right].expand(-1, -1, -1, bottom - top, -1)
        # the order the second layer's weights were trained on: row, column, west, east, north,
        # south, each for all channels
        order = [row[:, 0], column[:, 0], column[:, 1], column[:, 2], row[:, 1], row[:, 2]]
        return torch.cat(order, 1)


AXIAL_VIEWS = 6
# The far relation: its position code (the 8 offsets' codes are -1, -5/7, ..., 1), the log of
# its first cost per squared cell of distance, and its reach in rows and columns (a 10x10 map
# whole, a robot map's neighbourhood)
FAR_POSITION, FAR_LOG_COST, FAR_REACH = 0.0, -3.0, 12


# a squared distance past any reach: "no such cell within reach" (int16 leaves room for the
# two passes' additions)
FAR_BEYOND = 1 << 14
# cells per chunk of kinds in far_map: one large map's planes at a time stay in cache, while the
# small maps of a training batch take all kinds in one go
FAR_CHUNK_CELLS = 1 << 18
# far_map scores every cell pair of maps within reach while they have at most this many pairs
# (one 10x10 map: 10^4); a training batch takes the distance transforms, which are cheaper there
FAR_PAIRS = 1 << 16
# squared_distances takes a pass as one op over all 2R+1 shifts while they hold at most this
# many entries (per-op costs dominate such small planes), and shifts in place above it
FAR_UNFOLD_ENTRIES = 1 << 19


def squared_distances(marks: torch.Tensor, reach: int) -> torch.Tensor:
    """
    Return each cell's squared distance to the nearest marked cell, per map of marks (..., H, W).

    Only marks within `reach` rows and columns count; FAR_BEYOND or more where none does. The
    squared distance splits into rows and columns, so it is two exact passes of 2R+1 shifts,
    O(HWR). It depends on the grid alone (no gradient), so it runs in int16: a 512x512 plane
    is 512 KB. Small planes take each pass as one op over all shifts (FAR_UNFOLD_ENTRIES);
    large ones shift in place, which stays in cache.
    """
    d = torch.full(marks.shape, FAR_BEYOND, dtype=torch.int16, device=marks.device)
    d.masked_fill_(marks, 0)
    for dim in (-1, -2):
        n = d.shape[dim]
        r = min(reach, n - 1)
        padded = F.pad(d, [r, r] if dim == -1 else [0, 0, r, r], value=FAR_BEYOND)
        if d.numel() * (2 * r + 1) <= FAR_UNFOLD_ENTRIES:
            squares = (torch.arange(-r, r + 1, device=d.device) ** 2).to(d.dtype)
            d = (padded.unfold(dim, 2 * r + 1, 1) + squares).amin(-1)
            continue
        step = torch.empty_like(d)
        for s in range(1, r + 1):
            for start in (r - s, r + s):
                torch.add(padded.narrow(dim, start, n), s * s, out=step)
                torch.minimum(d, step, out=d)
    return d


@functools.lru_cache(maxsize=16)
def pair_distances(height: int, width: int, device=None) -> torch.Tensor:
    """(H*W, H*W): the squared distance between every two cells of a map (read only)."""
    rows, cols = torch.meshgrid(
        torch.arange(height, device=device), torch.arange(width, device=device), indexing='ij'
    )
    cells = torch.stack([rows.flatten(), cols.flatten()], 1).float()
    return ((cells[:, None] - cells[None]) ** 2).sum(-1)


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


def build_head(cfg: ModelConfig) -> OutputHead:
    return OutputHead(
        cfg.head,
        cfg.head_slope,
        cfg.gradient_cells,
        cfg.axial,
        cfg.head_text,
        inputs=3 if cfg.far else 2,
    )


class TRNet(nn.Module):
    """
    Text-conditioned relation network.

    With attention (t-RNetAttn) the relation MLP's weights are decoded from h_ij = sum_k
    alpha_ij(k) h(k) for each cell pair; without it (t-RNet) from the mean of the LSTM outputs, the
    same for every pair.

    Two ways to the same numbers. The reference (pair_forward) scores every cell pair of the map.
    The fast way uses that a pair's score, attention included, depends only on the two cells'
    kinds, their offset and the instruction: text_code scores each (kind_i, kind_j, offset) once
    per instruction, a table whatever the map size, and ground reads each pair's score from it.
    forward takes whichever scores fewer rows; both give the same values and gradients.
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
        self.head = build_head(cfg)
        sizes = [2 * cfg.embed_dim + 1, *cfg.mlp, 1]
        self.layer_shapes = list(zip(sizes[1:], sizes[:-1]))  # (out, in) per layer
        if cfg.far:
            self.far_log_cost = nn.Parameter(torch.tensor(FAR_LOG_COST))

    def split_params(self, params: torch.Tensor) -> list[torch.Tensor]:
        """
        Cut a parameter vector (..., 263) into the relation MLP's weights (..., out, in).

        One split, not a slice per layer: a slice's backward fills a zero tensor of the
        vector's size, per layer.
        """
        sizes = [out * inp for out, inp in self.layer_shapes]
        parts = params.split([*sizes, params.shape[-1] - sum(sizes)], -1)
        return [part.unflatten(-1, shape) for part, shape in zip(parts, self.layer_shapes)]

    @staticmethod
    def relation_mlp(
        weights: list[torch.Tensor], x: torch.Tensor, attention: torch.Tensor | None
    ) -> torch.Tensor:
        """
        Compute r = W3 tanh(W2 tanh(W1 x)) over pairs' inputs x (B, N, P, in).

        Without attention the weights are one set per map, (B, out, in). With attention the
        pair (i, j) uses W_ij = sum_k alpha_ij(k) W(k), the weights decoded from each word k
        (B, L, out, in), attention (B, N, P, L): W_ij x = sum_k alpha_ij(k) (W(k) x), one
        matmul per word and a weighted sum, never a weight matrix per pair.
        """
        if not weights:
            return x.squeeze(-1)
        if attention is None:
            # one weight set per map: each layer is one bmm of (out, in) by the pairs as
            # columns, (B, in, N * P); 2x faster than by N * P rows of `in`
            b, n, p, _ = x.shape
            x = x.reshape(b, n * p, -1).transpose(1, 2)
            for w in weights[:-1]:
                x = tanh(torch.bmm(w, x))
            return torch.bmm(weights[-1], x).view(b, n, p)
        for n, w in enumerate(weights):
            x = (attention.unsqueeze(-1) * torch.einsum('bnpi,bloi->bnplo', x, w)).sum(-2)
            if n < len(weights) - 1:
                x = tanh(x)
        return x.squeeze(-1)

    def relations(self, phi_i: torch.Tensor, phi_j: torch.Tensor, text: tuple):
        """
        Score every pair of a map: centres phi_i (B, N, k) against phi_j (B, N, P, k).

        Returns r (B, N, P) and the attention over words (B, N, P, L) (None without it).
        """
        words, mask, mean = text  # (B, L, 30), (B, L), (B, 30)
        rel = relative_positions(self.cfg.radius).to(phi_j.device)
        k = phi_j.shape[-1]
        attention = None
        if self.attention_on:
            # alpha_ij(k) ~ exp(h(k)^T A [phi_i; phi_j]); the score splits into an i part and
            # a j part, so it costs (B, N, L) + (B, N, P, L), not a product over all three.
            q = self.attn(words)  # (B, L, 2k)
            score = torch.einsum('bnd,bld->bnl', phi_i, q[..., :k]).unsqueeze(2) + torch.einsum(
                'bnpd,bld->bnpl', phi_j, q[..., k:]
            )
            score = score.masked_fill(~mask[:, None, None, :], float('-inf'))
            attention = score.softmax(-1)  # (B, N, P, L)
            # the decoder is linear and sum_k alpha = 1, so decoding h_ij equals the
            # alpha-weighted sum of the words' decoded parameters
            weights = self.split_params(self.decoder(words))  # (B, L, out, in) per layer
        else:
            weights = self.split_params(self.decoder(mean))  # (B, out, in) per layer
        first = self.first_layer(weights[0], phi_i, phi_j, rel, attention)
        return self.relation_mlp(weights[1:], tanh(first), attention), attention

    @staticmethod
    def first_layer(
        w1: torch.Tensor,
        phi_i: torch.Tensor,
        phi_j: torch.Tensor,
        rel: torch.Tensor,
        attention: torch.Tensor | None,
    ) -> torch.Tensor:
        """
        Compute W1 [phi_i; phi_j; l] for every pair: (B, N, P, out).

        The layer is linear, so it splits into an i term, a j term and a position term, each
        computed where it varies: per cell, per pair and per offset. No pair meets the
        (2k+1)-wide weight, which takes about 30% off the relation MLP's work on a map
        (PuddleWorld: 260 -> 180 multiply-adds a pair). With attention the words' terms are
        mixed by it, per pair.
        """
        b, m, p, k = phi_j.shape
        w_i, w_j, w_rel = w1[..., :k], w1[..., k:2 * k], w1[..., 2 * k]
        if attention is None:
            # one set of weights per map, (B, out, in): computed with the pairs as columns,
            # (B, out, N, P), the layout relation_mlp's bmm reads without a copy
            term_i = torch.bmm(w_i, phi_i.transpose(1, 2))[..., None]
            term_j = torch.bmm(w_j, phi_j.reshape(b, m * p, k).transpose(1, 2))
            first = term_i + term_j.view(b, -1, m, p) + w_rel[:, :, None, None] * rel
            return first.permute(0, 2, 3, 1)
        # per word (B, L, out, in): each term for every word, then the attention-weighted sum
        term_i = torch.einsum('bnd,blod->bnlo', phi_i, w_i)
        term_j = torch.einsum('bnpd,blod->bnplo', phi_j, w_j)
        return (
            torch.einsum('bnpl,bnlo->bnpo', attention, term_i)
            + torch.einsum('bnpl,bnplo->bnpo', attention, term_j)
            + rel[:, None] * torch.einsum('bnpl,blo->bnpo', attention, w_rel)
        )

    def table(self, kinds: torch.Tensor, kinds_j: torch.Tensor, text: tuple, rel: torch.Tensor):
        """
        Score every (kind_i, kind_j) of `kinds` x `kinds_j` at each position code of `rel` (P,).

        `kinds` and `kinds_j` are (K,), one table for every instruction, or (B, K), one each.
        Returns r (B, Ki * Kj, P), row i * Kj + j, and the attention over words of each row
        (B, Ki * Kj, L), or None without attention. A pair's attention has no position term,
        so a row mixes the words' weights once for all its positions, where a map's pairs
        would each mix their own. The first layer splits into an i, a j and a position term
        (first_layer), here computed per kind and per word before the mix. t-RNet is the
        same computation with one 'word', the LSTM outputs' mean, at weight 1.
        """
        words, mask, mean = text  # (B, L, 30), (B, L), (B, 30)
        embed = self.phi.embed.weight
        b, k = len(words), embed.shape[1]
        # (B, Ki, k), (B, Kj, k)
        phi_i, phi_j = (embed[kinds].expand(b, -1, -1) for kinds in (kinds, kinds_j))
        if not self.attention_on:
            words = mean[:, None]  # one 'word': t-RNet's weights, shared by every pair
        # each word's relation MLP, (B, L, out, in) per layer
        w1, *later_layers = self.split_params(self.decoder(words))
        n_words, out = w1.shape[1:3]
        # each kind's i and j terms for every word: (B, Ki, L, out), (B, Kj, L, out)
        term_i = (phi_i @ w1[..., :k].flatten(1, 2).mT).unflatten(-1, (n_words, out))
        term_j = (phi_j @ w1[..., k:2 * k].flatten(1, 2).mT).unflatten(-1, (n_words, out))
        # the later layers' weights side by side, each as (in, out): x @ w, no transpose
        later = torch.cat([w.mT.flatten(-2) for w in later_layers], -1)  # (B, L, 110)
        if self.attention_on:
            # alpha ~ exp(h^T A [phi_i; phi_j]): an i part and a j part, (B, L, Ki, Kj). The
            # softmax runs over dim 1: this torch's CPU softmax is 16x slower over a last
            # dimension of about 12 (2 ms for a training batch)
            q = self.attn(words)  # (B, L, 2k)
            score = (q[..., :k] @ phi_i.mT)[..., :, None] + (q[..., k:] @ phi_j.mT)[..., None, :]
            alpha = score.masked_fill(~mask[:, :, None, None], float('-inf')).softmax(1)
            # the terms mixed per (kind_i, kind_j): (B, Ki, Kj, out)
            fixed = alpha.permute(0, 2, 3, 1) @ term_i + (
                alpha.permute(0, 3, 2, 1) @ term_j
            ).transpose(1, 2)
            rows = alpha.flatten(2).transpose(1, 2)  # (B, R, L)
            slope = rows @ w1[..., 2 * k]  # (B, R, out): the position term's weights, mixed
            later = rows @ later  # (B, R, 110): each row's own weights, mixed once
        else:
            fixed = term_i[:, :, None, 0] + term_j[:, None, :, 0]
            slope = w1[..., 2 * k]  # (B, 1, out)
        x = tanh(fixed.flatten(1, 2)[:, :, None] + rel[:, None] * slope[:, :, None])
        r, p = x.shape[1:3]
        if not self.attention_on:  # one set per instruction: the rows' positions are one bmm's
            x = x.reshape(b, 1, r * p, -1)
        shapes = self.layer_shapes[1:]
        parts = later.split([n_out * n_in for n_out, n_in in shapes], -1)
        for n, (w, (n_out, n_in)) in enumerate(zip(parts, shapes)):
            if n < len(shapes) - 1:
                x = tanh(x @ w.unflatten(-1, (n_in, n_out)))
            else:  # the output (one unit): a product and a sum, not a matmul of one column
                x = (x * w.unsqueeze(-2)).sum(-1)
        return x.view(b, r, p), rows if self.attention_on else None

    def forward(
        self,
        grids: torch.Tensor,
        tokens: torch.Tensor,
        return_aux: bool = False,
        reference: bool = False,
    ):
        """
        Value maps (B, H, W) for grids (B, H, W) and tokens (B, L).

        reference=True scores every cell pair of the maps (the definition); otherwise each
        map's relation table over the kinds it holds is used when it is the cheaper (a table
        row is a (kind_i, kind_j) pair with a column per offset, a map row a cell with its 8
        neighbours). Without attention that is when it has fewer rows than the maps have
        cells: a 10x10 map with all 12 kinds has 12 x 13 = 156 rows against 100 cells. With
        attention each of a map's pairs mixes the L words' weights, a table row mixes them
        once for all its offsets, so the table wins on any map but the smallest.
        """
        kinds = kinds_per_map(grids, self.phi.embed.num_embeddings, self.phi.off_map)
        n_kinds = kinds.shape[1]
        rows, cells = n_kinds * (n_kinds + 1), grids.shape[1] * grids.shape[2]
        offsets = len(neighbour_offsets(self.cfg.radius))
        words = tokens.shape[1] if self.attention_on else 0
        if reference or rows * (offsets + words) >= cells * offsets * max(words, 1):
            return self.pair_forward(grids, tokens, return_aux)
        return self.ground(grids, self.text_code(tokens, kinds), return_aux)

    def pair_forward(self, grids: torch.Tensor, tokens: torch.Tensor, return_aux: bool = False):
        """Score every cell against each of its 8 neighbours: the reference."""
        b, h, w = grids.shape
        radius = self.cfg.radius
        phi = self.phi(grids)  # (B, H+2, W+2, k)
        phi_i = phi[:, radius:radius + h, radius:radius + w].flatten(1, 2)  # (B, N, k)
        phi_j = torch.stack(shifted(phi, radius), dim=3).flatten(1, 2)  # (B, N, 8, k)
        text = self.text(tokens)
        r, attention = self.relations(phi_i, phi_j, text)  # (B, N, 8)
        z1 = r.max(dim=-1).values.view(b, h, w)
        far = None
        if self.cfg.far:  # its score has no offset term: a table over the kinds present
            kinds = present_kinds(grids, self.cfg.n_entities)
            far = self.far_map(grids, kinds, self.far_table(text, kinds))
        values = self.head(z1, self.decoder(text[2])[:, -self.head.code_size:], far)  # h's last
        # how much each word mattered, averaged over all pairs
        word_attention = None if attention is None else attention.mean(dim=(1, 2))
        return outputs(values, z1, word_attention, return_aux)

    def text_code(self, tokens: torch.Tensor, kinds: torch.Tensor | None = None) -> dict:
        """
        All that an instruction contributes, for maps of any size.

        The relation table r over (kind_i, kind_j, offset) as (B, Ki * Kj, 8), row
        i * Kj + j; the attention over words per kind pair (B, Ki * Kj, L), the same at every
        offset (its score has no offset term), or None; and the head's code (B, code_size).
        The centre kinds are `kinds` (default: all), the neighbour kinds those and the off-map
        one: a caller that keeps this per instruction grounds it on any map with a gather and a
        max. `kinds` (B, K): a table of each instruction's own kinds (kinds_per_map).
        """
        if kinds is None:
            kinds = torch.arange(self.cfg.n_entities, device=tokens.device)
        off_map = kinds.new_full((*kinds.shape[:-1], 1), self.phi.off_map)
        kinds_j = torch.cat([kinds, off_map], -1)
        n_nbrs = len(neighbour_offsets(self.cfg.radius))
        text = self.text(tokens)
        # the far relation's position is a ninth column of the same rows: one pass scores both
        # (far_table's (kind_i, kind_j) are the rows whose j is not off the map)
        rel = relative_positions(self.cfg.radius).to(tokens.device)
        if self.cfg.far:
            rel = torch.cat([rel, rel.new_tensor([FAR_POSITION])])
        r, attention = self.table(kinds, kinds_j, text, rel)
        far = None
        if self.cfg.far:
            far = r[..., n_nbrs].unflatten(1, (kinds.shape[-1], kinds_j.shape[-1]))[..., :-1]
        return {
            'kinds': kinds,
            'relations': r[..., :n_nbrs],
            'attention': attention,
            'head': self.decoder(text[2])[:, -self.head.code_size:],
            'far': far,
        }

    def kind_rows(self, grids: torch.Tensor, kinds: torch.Tensor) -> torch.Tensor:
        """
        Return each cell's row in a table over `kinds`, (B, H*W); a kind it lacks: an error.

        `kinds` (K,): one table for every map; (B, K): one per map.
        """
        kinds = kinds.expand(len(grids), -1)  # a shared table: the same kinds for every map
        row = torch.full((len(grids), self.phi.embed.num_embeddings), -1, device=grids.device)
        row.scatter_(1, kinds, torch.arange(kinds.shape[1], device=grids.device).expand_as(kinds))
        cells = row.gather(1, grids.flatten(1))
        if cells.min() < 0:
            missing = sorted(set(grids.flatten(1)[cells < 0].tolist()))
            raise ValueError(f'the relation table lacks entity kinds {missing} of the grid')
        return cells

    def far_table(self, text: tuple, kinds: torch.Tensor) -> torch.Tensor:
        """Score each (kind_i, kind_j) of `kinds` with the far relation: (B, K, K)."""
        r, _ = self.table(kinds, kinds, text, torch.tensor([FAR_POSITION], device=kinds.device))
        return r.view(-1, kinds.shape[-1], kinds.shape[-1])

    def far_map(
        self,
        grids: torch.Tensor,
        kinds: torch.Tensor,
        table: torch.Tensor,
        rows: torch.Tensor | None = None,
    ):
        """
        Return the far relation map (B, H, W): per cell i, max over j of far - cost d^2.

        j runs over the cells within FAR_REACH rows and columns of i, d = |i - j|, and far is
        the far relation's score of (kind_i, kind_j), from `table`. A few maps no larger than
        the reach take that definition as it stands: every cell pair, one gather (FAR_PAIRS).
        Otherwise a cell's own kind a is at distance 0, so far(a, a) is its floor, and a kind k can
        raise it only where far(a, k) - cost * d^2 > far(a, a): only such kinds are measured,
        and only as far as that gain reaches (exact, and a fraction of the work on a large
        map). Per kind k, each cell adds its row's far(a, k) to -cost times its squared
        distance to the nearest k. `rows`: the cells' kind_rows, when the caller has them.
        """
        b, h, w = grids.shape
        if rows is None:
            rows = self.kind_rows(grids, kinds)  # (B, H*W): each cell's row of the table
        table = table.expand(b, -1, -1)
        cost = self.far_log_cost.exp()
        n = kinds.shape[-1]
        if h <= FAR_REACH + 1 and w <= FAR_REACH + 1 and b * (h * w) ** 2 <= FAR_PAIRS:
            pairs = (rows[:, :, None] * n + rows[:, None, :]).flatten(1)  # (B, N * N)
            scores = table.flatten(1).gather(1, pairs).view(b, h * w, h * w)
            return (scores - cost * pair_distances(h, w, grids.device)).amax(-1).view(b, h, w)
        out = table.diagonal(dim1=1, dim2=2).gather(1, rows).view(b, h, w)  # far(a, a)
        present = torch.bincount(rows.flatten(), minlength=n) > 0
        gain = (table - table.diagonal(dim1=1, dim2=2)[..., None])[:, present]  # (B, A, K)
        gain = gain.detach().amax(dim=(0, 1))  # per kind k, over the kinds a present
        useful = ((gain > 0) & present).nonzero().flatten()
        if not len(useful):
            return out
        top = gain[useful].max()
        reach = min(int(torch.sqrt(top / cost.detach())), FAR_REACH)
        # a cell with no k within reach scores at most floor + gain - cost * FAR_BEYOND: below
        # its floor unless the gain is that large, so only then must it be masked out
        masked = bool(top >= cost.detach() * FAR_BEYOND)
        # each cell's far(a, k) for the useful kinds k: one lookup in the B * K rows of the
        # tables, (U, B, H, W)
        lookup = table[:, :, useful].permute(2, 0, 1).reshape(len(useful), b * n)
        cells = (rows + torch.arange(b, device=grids.device)[:, None] * n).flatten()
        scores = lookup.index_select(1, cells).view(len(useful), b, h, w)
        chunk = max(1, FAR_CHUNK_CELLS // (b * h * w))
        for start in range(0, len(useful), chunk):
            ks = kinds[..., useful[start:start + chunk]].expand(b, -1)  # (B, U): each map's
            with torch.no_grad():
                dist = squared_distances(grids[:, None] == ks[:, :, None, None], reach)
            near = scores[start:start + chunk].transpose(0, 1).addcmul(dist, -cost)
            if masked:
                near = near.masked_fill(dist >= FAR_BEYOND, float('-inf'))
            out = torch.maximum(out, near.amax(1))  # over the chunk's kinds, per map
        return out

    def ground(self, grids: torch.Tensor, code: dict, return_aux: bool = False):
        """Value maps of grids (B, H, W) for a text_code of B instructions (or of 1 for all)."""
        b, h, w = grids.shape
        kinds, relations = code['kinds'], code['relations']  # (B or 1, Ki * Kj, P)
        n_rows, p = relations.shape[1:]
        radius = self.cfg.radius
        # each pair's (kind_i, kind_j) row, i * Kj + j, with j the off-map row past the border
        n_kinds = kinds.shape[-1]
        centre = self.kind_rows(grids, kinds)  # (B, N)
        around = F.pad(centre.view(b, h, w), (radius,) * 4, value=n_kinds)
        neighbours = torch.stack(shifted(around, radius), -1).view(b, h * w, p)
        pairs = centre[..., None] * (n_kinds + 1) + neighbours  # (B, N, P)
        # one gather from the flattened table: the pair's row * P + its offset
        index = (pairs * p + torch.arange(p, device=grids.device)).view(b, -1)
        r = relations.flatten(1).expand(b, -1).gather(1, index)
        z1 = r.view(b, h * w, p).amax(-1).view(b, h, w)
        far = None if code['far'] is None else self.far_map(grids, kinds, code['far'], centre)
        values = self.head(z1, code['head'].expand(b, -1), far)
        word_attention = None
        if return_aux and code['attention'] is not None:
            # the mean over the map's pairs: each kind pair's attention times its pair count
            if b > 1:
                pairs = pairs + torch.arange(b, device=grids.device)[:, None, None] * n_rows
            counts = torch.bincount(pairs.flatten(), minlength=b * n_rows).to(relations.dtype)
            word_attention = (counts.view(b, 1, n_rows) @ code['attention'].expand(b, -1, -1))[
                :, 0
            ] / (p * h * w)
        return outputs(values, z1, word_attention, return_aux)


class TCNN(nn.Module):
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
        self.text = TextEncoder(cfg)
        # a 3x3 kernel per embedding dimension, then the head's code: 66 for k = 7
        kernel = 9 * cfg.embed_dim
        self.decoder = nn.Linear(cfg.hidden, kernel + head_code_size(cfg.head, cfg.head_text))
        self.head = build_head(cfg)

    def forward(self, grids: torch.Tensor, tokens: torch.Tensor, return_aux: bool = False):
        return self.ground(grids, self.text_code(tokens), return_aux)

    def text_code(self, tokens: torch.Tensor) -> dict:
        """All that an instruction contributes: the kernel (B, k, 3, 3) and the head's code."""
        vec = self.decoder(self.text(tokens)[2])
        kernels = vec[:, :9 * self.cfg.embed_dim].unflatten(1, (self.cfg.embed_dim, 3, 3))
        return {'kernels': kernels, 'head': vec[:, 9 * self.cfg.embed_dim:]}

    def ground(self, grids: torch.Tensor, code: dict, return_aux: bool = False):
        """Value maps of grids (B, H, W) for a text_code of B instructions (or of 1 for all)."""
        b, h, w = grids.shape
        k = self.cfg.embed_dim
        phi = self.phi(grids).permute(0, 3, 1, 2)  # (B, k, H+2, W+2)
        kernels = code['kernels'].expand(b, -1, -1, -1).reshape(b, k, 3, 3)
        # one kernel per example: a grouped convolution over the batch
        z1 = F.conv2d(phi.reshape(1, b * k, h + 2, w + 2), kernels, groups=b).view(b, h, w)
        values = self.head(z1, code['head'].expand(b, -1))
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
        return self.ground(grids, self.text_code(tokens), return_aux)

    def text_code(self, tokens: torch.Tensor) -> dict:
        """All that an instruction contributes: the text vector (B, 7)."""
        return {'text': self.to_text(self.text(tokens)[2])}

    def ground(self, grids: torch.Tensor, code: dict, return_aux: bool = False):
        """Value maps of grids (B, H, W) for a text_code of B instructions (or of 1 for all)."""
        b, h, w = grids.shape
        state = self.state(self.phi(grids).permute(0, 3, 1, 2))
        text = code['text'].expand(b, -1)[:, :, None, None].expand(-1, -1, h, w)
        values = self.deconv(torch.cat([state, text], 1)).squeeze(1)
        return outputs(values, torch.zeros_like(values), None, return_aux)


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
