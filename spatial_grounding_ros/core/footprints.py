# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Landmarks drawn over several cells: a robot map's sink, not PuddleWorld's one-cell objects.

A landmark's footprint (its 8-connected cells of one kind) is one referent. An offset is
taken from the footprint's edge on its side, along the footprint's middle: "one below the
sink" is the cell under the middle of its bottom row, "two to the left of" two cells left of
the middle of its left column, "below and to the left of" past its bottom-left corner, and
"the sink" itself, or a relation with no side (closest, between, an extreme), is its middle
cell. Each footprint of a named kind becomes one cell there, its anchor, before the network
reads the map: the network was trained on one-cell landmarks, and the anchor is the cell whose
one-cell relation is the footprint's. The footprint's other cells become an obstacle, so no
goal lands inside a landmark unless the landmark itself is the goal.
"""

from __future__ import annotations

import numpy as np


def footprints(grid: np.ndarray, kind: int) -> list[np.ndarray]:
    """Return each 8-connected group of a kind's cells, as (n, 2) arrays of (row, col)."""
    mask = grid == kind
    if not touching(mask):  # each cell its own group: a large map's objects, at numpy's pace
        return list(np.argwhere(mask)[:, None])
    left = {(int(r), int(c)) for r, c in np.argwhere(mask)}
    groups = []
    while left:
        todo = [left.pop()]
        group = []
        while todo:
            r, c = todo.pop()
            group.append((r, c))
            for dr in (-1, 0, 1):
                for dc in (-1, 0, 1):
                    if (r + dr, c + dc) in left:
                        left.remove((r + dr, c + dc))
                        todo.append((r + dr, c + dc))
        groups.append(np.array(sorted(group)))
    return groups


def touching(mask: np.ndarray) -> bool:
    """Say whether any two cells of a mask are 8-neighbours."""
    m = np.pad(mask, 1)
    core = m[1:-1, 1:-1]
    # each pair once: the neighbour to the east, south-west, south and south-east
    return any(
        (core & m[1 + dr:m.shape[0] - 1 + dr, 1 + dc:m.shape[1] - 1 + dc]).any()
        for dr, dc in ((0, 1), (1, -1), (1, 0), (1, 1))
    )


def anchor(cells: np.ndarray, side: tuple[int, int]) -> tuple[int, int]:
    """
    Return the cell of a footprint that stands for it when an offset leaves it on `side`.

    `side` is the offset's sign per axis ((1, 0): below). On an axis the offset moves along,
    the anchor is the footprint's last cell that way; on the other, its middle (of an even
    extent, the lower index). A footprint that does not hold that cell (an L shape) gives its
    cell nearest to it.
    """
    point = []
    for axis, s in enumerate(side):
        lo, hi = int(cells[:, axis].min()), int(cells[:, axis].max())
        point.append(hi if s > 0 else lo if s < 0 else (lo + hi) // 2)
    nearest = cells[((cells - np.array(point)) ** 2).sum(1).argmin()]
    return int(nearest[0]), int(nearest[1])


def reduce_footprints(
    grid: np.ndarray, sides: dict[int, tuple[int, int]], obstacle: int
) -> np.ndarray:
    """
    Return the grid with each footprint of the kinds in `sides` reduced to its anchor.

    `sides`: kind -> the side its offset leaves it on ((0, 0): none). Each footprint of more
    than one cell keeps only its anchor; its other cells become `obstacle`.
    """
    out = grid.copy()
    for kind, side in sides.items():
        for cells in footprints(grid, kind):
            if len(cells) < 2:
                continue
            out[cells[:, 0], cells[:, 1]] = obstacle
            out[anchor(cells, side)] = kind
    return out


def side_of(offset: tuple[int, int]) -> tuple[int, int]:
    """Return an offset's sign per axis: the side of a landmark it leaves on."""
    return int(np.sign(offset[0])), int(np.sign(offset[1]))


def nearest_cell(grid: np.ndarray, kinds: list[int], cell: tuple[int, int]):
    """Return the cell of any of `kinds` nearest `cell` (Euclidean), or None."""
    where = np.argwhere(grid == kinds[0] if len(kinds) == 1 else np.isin(grid, kinds))
    if not len(where):
        return None
    nearest = where[((where - np.asarray(cell)) ** 2).sum(1).argmin()]
    return int(nearest[0]), int(nearest[1])
