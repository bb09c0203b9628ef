# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
A map's side of TRNet.ground: each cell's row of the relation table and its pairs' rows.

They depend on the map and the table's kinds, never on the instruction: a node grounds each
instruction on the map it holds, so at inference a small map's are computed once and kept
(some 0.15 ms of a 10x10 map's 0.5 ms in the network; the instruction's side is the text
code, kept per instruction by the grounder).
"""

from __future__ import annotations

import collections
from dataclasses import dataclass, field

import torch
import torch.nn.functional as F

from .encoders import kind_rows, shifted

# a map of more cells than this is grounded (without gradients) one neighbour offset at a time:
# on small maps one gather of all offsets costs fewer calls
GATHER_BY_OFFSET_CELLS = 64 * 64
# maps kept at inference (a node holds one; a grounding with mirror images adds one batch)
MAPS_KEPT = 4
_KEPT: collections.OrderedDict = collections.OrderedDict()


@dataclass
class MapCells:
    """
    One batch of maps' rows in a relation table over (kind_i, kind_j), row i * Kj + j.

    `centre` (B, H*W): each cell's kind's row i; `pairs`: each pair's row, as one (B, H, W, P)
    tensor or one (B, H, W) per offset; `index` (B, H*W*P): the table entry of each pair at
    its offset (row * P + offset), when gathered at once (else None).
    """

    centre: torch.Tensor
    pairs: list[torch.Tensor]
    index: torch.Tensor | None
    n_rows: int
    _counts: torch.Tensor | None = field(default=None, repr=False)

    def counts(self) -> torch.Tensor:
        """Return how often each map holds each table row (B * n_rows,) (pair_counts)."""
        if self._counts is None:
            self._counts = pair_counts(self.pairs, self.n_rows)
        return self._counts


def map_cells(grids: torch.Tensor, kinds: torch.Tensor, n_kinds: int, radius: int, p: int):
    """
    Return the MapCells of grids (B, H, W) in a table over `kinds` (K,) or (B, K).

    Kinds_j are `kinds` and the off-map kind (row K, past the border); `n_kinds`: the entity
    table's rows; `p` the table's offsets. Kept (MAPS_KEPT, keyed by the cells) at inference,
    on the CPU, for one table over all maps on maps that gather at once: the same tensors as
    computed, read only.
    """
    if not (torch.is_inference_mode_enabled() and kinds.dim() == 1 and grids.device.type == 'cpu'
            and grids.shape[1] * grids.shape[2] <= GATHER_BY_OFFSET_CELLS):
        return compute_map_cells(grids, kinds, n_kinds, radius, p)
    key = (grids.shape, grids.numpy().tobytes(), kinds.numpy().tobytes(), n_kinds, radius, p)
    cells = _KEPT.pop(key, None)
    if cells is None:
        cells = compute_map_cells(grids, kinds, n_kinds, radius, p)
        if len(_KEPT) >= MAPS_KEPT:
            _KEPT.popitem(last=False)
    _KEPT[key] = cells
    return cells


def compute_map_cells(grids: torch.Tensor, kinds: torch.Tensor, n_kinds: int, radius: int, p: int):
    """Return map_cells' MapCells, computed."""
    b, h, w = grids.shape
    k = kinds.shape[-1]
    centre = kind_rows(grids, kinds, n_kinds)  # (B, N); a kind the table lacks: an error
    around = F.pad(centre.view(b, h, w), (radius,) * 4, value=k)
    first = centre.view(b, h, w) * (k + 1)
    pairs = [first + neighbour for neighbour in shifted(around, radius)]
    index = None
    if torch.is_grad_enabled() or h * w <= GATHER_BY_OFFSET_CELLS:
        pairs = [torch.stack(pairs, -1)]  # (B, H, W, P)
        index = (pairs[0] * p + torch.arange(p, device=grids.device)).view(b, -1)
    return MapCells(centre, pairs, index, k * (k + 1))


def pair_counts(pairs: list[torch.Tensor], n_rows: int) -> torch.Tensor:
    """Return how often each map holds each table row (B * n_rows,), from its pairs' rows."""
    b = len(pairs[0])
    counts = 0
    for pair in pairs:  # (B, H, W) per offset, or (B, H, W, P) all at once
        maps = torch.arange(b, device=pair.device).view(b, *[1] * (pair.dim() - 1)) * n_rows
        counts = counts + torch.bincount((pair + maps).flatten(), minlength=b * n_rows)
    return counts
