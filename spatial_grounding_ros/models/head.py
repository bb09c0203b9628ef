# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""The output network: Z1 (and the far map) with the gradient maps in, the value map out."""

from __future__ import annotations

import functools

import torch
from torch import nn
import torch.nn.functional as F

from .config import head_code_size, ModelConfig
from .traces import traced


def outputs(values: torch.Tensor, z1: torch.Tensor, attention, return_aux: bool):
    """Return a model's output: the value map, and with return_aux Z1 and the attention."""
    return (values, {'relation_map': z1, 'attention': attention}) if return_aux else values


# One map of up to this many cells at inference runs a trace of the head (models.traces):
# there its time is mostly Python around some 60 small tensor ops (0.53 -> 0.35 ms at 10x10)
TRACED_CELLS = 32 * 32


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

    with torch.inference_mode(False):  # kept: a plain tensor, whichever mode first asks
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
    PQ 0.881 -> 0.906, for a few milliseconds more on a large map (docs/benchmarks.md). No final
    ReLU: true values go negative (puddles, down to about -3.3), so a ReLU would clip those
    cells to 0, an error no training removes.

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
        if (layout is None and h * w <= TRACED_CELLS and not torch.is_grad_enabled()
                and not torch.jit.is_tracing()):
            return self.traced(z1, code, far)
        beta, film = code[:, :3], code[:, 3:] if self.film else None
        # int(): in a trace the sizes are traced values; as ints the maps are its constant
        gradients = gradient_maps(int(h), int(w), z1.device, self.gradient_cells).view(3, h * w)
        z2 = (beta @ gradients).view(-1, h, w)
        x = torch.stack([z1, z2] if far is None else [z1, z2, far], dim=1)
        if not (self.axial or self.film):
            return self.tiled(x, first=0, layout=layout)
        # the views are map-wide: the first layer runs on the whole map (8 channels a cell)
        x = self.convolve(x, first=0, last=1, film=film, layout=layout)
        views = {1: [AxialViews(x)]} if self.axial else None
        return self.tiled(x, first=1, views=views, layout=layout)

    def traced(self, z1: torch.Tensor, code: torch.Tensor, far: torch.Tensor | None):
        """
        Run forward as a trace of it for these inputs' shapes (models.traces.traced).

        The map's size fixes the gradient maps and each choice forward makes (layout, tiles,
        views). Only without gradients: training runs forward itself.
        """
        # made before, the gradient maps are a constant of a trace, not ops of it
        gradient_maps(*z1.shape[1:], z1.device, self.gradient_cells)
        return traced(self, lambda: self, (z1, code) if far is None else (z1, code, far))

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
            # channels-last is oneDNN's fast layout on CPU for batches and large maps; one map
            # of up to 96x96 runs faster in the plain layout (docs/benchmarks.md). The bench
            # times both.
            big = x.shape[0] > 1 or x.shape[2] * x.shape[3] > 96 * 96
            layout = torch.channels_last if big else torch.contiguous_format
        x = x.contiguous(memory_format=layout)
        for n in range(first, last):
            if views and views.get(n):
                x = self.conv_with_views(self.convs[n], x, views[n], window)
            else:
                x = self.convs[n](x)
            if n == 0 and film is not None:
                scale, shift = film[..., None, None].chunk(2, dim=1)
                x = x * (1 + scale) + shift
            if n < len(self.convs) - 1:
                x = F.leaky_relu(x, self.slope, inplace=True)  # the conv's own output
        return x[:, 0] if last == len(self.convs) else x

    @staticmethod
    def conv_with_views(conv: nn.Conv2d, x: torch.Tensor, views: list, window) -> torch.Tensor:
        """
        Run `conv` on x (B, C, h, w) with the views' window of the map joined to its channels.

        A view is constant along a row or a column, so inference convolves its profiles instead
        (AxialViews.convolved): the same sums, without the 6C map-sized channels, at a sixth
        of the layer's work on a large map. Training (and maps of up to 32x32 cells, where a
        few more calls cost more than they save) convolves them joined, as the weights learned;
        the map's size, not the tile's, decides, so a tiled map is grounded the same way.
        """
        if torch.is_grad_enabled() or min(v.cells for v in views) <= 32 * 32:
            return conv(torch.cat([x, *(v.window(*window) for v in views)], 1))
        c = x.shape[1]
        out = F.conv2d(x, conv.weight[:, :c], conv.bias, padding=1)
        for k, v in enumerate(views):
            out += v.convolved(conv.weight[:, c + k * 6 * c: c + (k + 1) * 6 * c], window)
        return out


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
        self.cells = x.shape[2] * x.shape[3]  # of the map
        low, cols, rows = extremes(x)

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

    def convolved(self, weight: torch.Tensor, window) -> torch.Tensor:
        """
        Return a 3x3 convolution (zero padding) of window(*window) by `weight` (O, 6C, 3, 3).

        Each view is constant along its row (or column), so at cell (i, j) the kernel's three
        taps across it add up to one weight: a convolution of the view's profile along the
        column (or row) with the kernel summed across, except in the window's first and last
        column (row), where the zero padding drops a tap. (B, O, h, w), without the bias: the
        row views' part plus the column views', one outer sum of their profiles.
        """
        top, bottom, left, right = window
        blocks = weight.unflatten(1, (AXIAL_VIEWS, -1))  # the order of window()'s channels
        rows = self.by_row[..., top:bottom].flatten(1, 2)  # (B, 3C, h): row, north, south
        columns = self.by_column[..., left:right].flatten(1, 2)  # (B, 3C, w): column, west, east
        by_row = across(rows, blocks[:, [0, 4, 5]].flatten(1, 2))  # (B, O, h, 4)
        # a column view's taps along the rows are the kernel's rows: transposed
        by_column = across(columns, blocks[:, [1, 2, 3]].flatten(1, 2).transpose(2, 3))
        return outer_sum(by_row, by_column)


def extremes(x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """
    Return x's (B, C, H, W) minimum (B, C, 1), column maxima (B, C, W) and row maxima (B, C, H).

    At inference a channels-last x is reduced along its own layout (the reductions across the
    channels' stride are ten times slower at 512x512); the same values, maxima being exact.
    Training keeps amax: its gradient splits among equal maxima, as the weights learned.
    """
    plain = x.is_contiguous() or not x.is_contiguous(memory_format=torch.channels_last)
    if torch.is_grad_enabled() or plain:
        return x.amin(dim=(2, 3))[..., None], x.amax(dim=2), x.amax(dim=3)
    cells = x.permute(0, 2, 3, 1)  # (B, H, W, C), contiguous
    low = cells.amin(1).amin(1)[..., None]
    cols = cells.amax(1).transpose(1, 2)
    rows = F.max_pool2d(x, (1, x.shape[3]))[..., 0]
    return low, cols, rows


def across(profile: torch.Tensor, weight: torch.Tensor) -> torch.Tensor:
    """
    Convolve a profile (B, C, m) by a 3x3 `weight` (O, C, along, across): (B, O, m, 4).

    The map is the profile repeated across (a row view: along the rows, repeated over the
    columns). Taps across sum to one 1-D kernel; the first and last cells across lose the tap
    the zero padding covers, and a map one cell across loses both. The four: an inner cell
    across, the first, the last, a cell alone.
    """
    sums = [weight.sum(3), weight[..., 1:].sum(3), weight[..., :2].sum(3), weight[..., 1]]
    o = weight.shape[0]
    return F.conv1d(profile, torch.cat(sums), padding=1).unflatten(1, (4, o)).permute(0, 2, 3, 1)


def outer_sum(by_row: torch.Tensor, by_column: torch.Tensor) -> torch.Tensor:
    """
    Return the (B, O, h, w) sum of a row part and a column part given as across()'s four.

    A row part's value at (i, j) is its i-th entry's inner one for j inner, its first or last
    at the edge columns (alone: one column); a column part's the same, rows and columns
    swapped. The inner cells are one broadcast sum, the border rows and columns set after.
    """
    h, w = by_row.shape[2], by_column.shape[2]

    def which(n: int) -> list[int]:  # across()'s entry for each of n cells across
        return [3] if n == 1 else [1, *[0] * (n - 2), 2]

    if h < 3 or w < 3:  # a thin window: each part in full
        return by_row[..., which(w)] + by_column[..., which(h)].transpose(2, 3)
    out = by_row[..., 0, None] + by_column[..., None, :, 0]
    out[..., 0, :] = by_row[..., 0, which(w)] + by_column[..., 1]
    out[..., -1, :] = by_row[..., -1, which(w)] + by_column[..., 2]
    out[..., :, 0] = by_row[..., 1] + by_column[..., 0, which(h)]
    out[..., :, -1] = by_row[..., 2] + by_column[..., -1, which(h)]
    return out


AXIAL_VIEWS = 6


def build_head(cfg: ModelConfig) -> OutputHead:
    return OutputHead(
        cfg.head,
        cfg.head_slope,
        cfg.gradient_cells,
        cfg.axial,
        cfg.head_text,
        inputs=3 if cfg.far else 2,
    )
