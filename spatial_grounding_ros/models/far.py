# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""The far relation: each cell against every cell within reach, discounted by distance."""

from __future__ import annotations

import functools

import torch
import torch.nn.functional as F


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
    with torch.inference_mode(False):  # kept: a plain tensor, whichever mode first asks
        rows, cols = torch.meshgrid(
            torch.arange(height, device=device), torch.arange(width, device=device), indexing='ij'
        )
        cells = torch.stack([rows.flatten(), cols.flatten()], 1).float()
        return ((cells[:, None] - cells[None]) ** 2).sum(-1)


def far_map(
    grids: torch.Tensor,
    kinds: torch.Tensor,
    table: torch.Tensor,
    cost: torch.Tensor,
    rows: torch.Tensor,
) -> torch.Tensor:
    """
    Return the far relation map (B, H, W): per cell i, max over j of far - cost d^2.

    j runs over the cells within FAR_REACH rows and columns of i, d = |i - j|, and far is
    the far relation's score of (kind_i, kind_j), from `table` (B or 1, K, K) over `kinds`
    (K,) or (B, K); `rows` (B, H*W) is each cell's row of that table (encoders.kind_rows) and
    `cost` the learned cost per squared cell of distance. A few maps no larger than the reach
    take that definition as it stands: every cell pair, one gather (FAR_PAIRS). Otherwise a
    cell's own kind a is at distance 0, so far(a, a) is its floor, and a kind k can raise it
    only where far(a, k) - cost * d^2 > far(a, a): only such kinds are measured, and only as
    far as that gain reaches (exact, and a fraction of the work on a large map). Per kind k,
    each cell adds its row's far(a, k) to -cost times its squared distance to the nearest k.
    """
    b, h, w = grids.shape
    table = table.expand(b, -1, -1)
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
