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
    """
    Return each 8-connected group of a kind's cells, as (n, 2) arrays of (row, col).

    The groups come in the order of their first cell (row by row), each group's cells in
    that order too.
    """
    cells, roots = _groups(grid == kind)
    if roots is None:  # each cell its own group
        return list(cells[:, None])
    order = np.argsort(roots, kind='stable')  # by group, each group's cells in row order
    starts = np.flatnonzero(np.diff(roots[order], prepend=-1))
    return np.split(cells[order], starts[1:])


def count_footprints(grid: np.ndarray, kind: int) -> int:
    """Return how many 8-connected groups of a kind's cells a map holds."""
    cells, roots = _groups(grid == kind)
    return len(cells) if roots is None else int((roots == np.arange(len(roots))).sum())


def _groups(mask: np.ndarray):
    """
    Return a mask's cells (n, 2), row by row, and each cell's group: its first cell's index.

    The group is None when no two cells touch. Groups are joined in numpy, a few rounds of
    hooking each group onto the lowest one it touches and then following the hooks: a large
    map's objects cost numpy's pace, not one Python step per cell.
    """
    cells = np.argwhere(mask)
    if len(cells) < 2 or not touching(mask):
        return cells, None
    index = np.full(mask.shape, -1, dtype=np.int64)
    index[cells[:, 0], cells[:, 1]] = np.arange(len(cells))
    a, b = _touching_pairs(index)
    root = np.arange(len(cells))
    while True:
        ra, rb = root[a], root[b]
        low, high = np.minimum(ra, rb), np.maximum(ra, rb)
        apart = low != high
        if not apart.any():
            return cells, root
        np.minimum.at(root, high[apart], low[apart])  # each hooked root onto a lower one
        while True:  # follow the hooks until every cell holds its group's root
            hop = root[root]
            if np.array_equal(hop, root):
                break
            root = hop


def neighbours(grid: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """
    Return views (a, b) of a 2-D array where b holds each a-cell's 8-neighbour, each pair once.

    One view pair per direction: the neighbour to the east, south-west, south and south-east.
    """
    h, w = grid.shape
    out = []
    for dr, dc in ((0, 1), (1, -1), (1, 0), (1, 1)):
        c0, c1 = max(0, -dc), w - max(0, dc)
        out.append((grid[0:h - dr, c0:c1], grid[dr:h, c0 + dc:c1 + dc]))
    return out


def touching(mask: np.ndarray) -> bool:
    """Say whether any two cells of a mask are 8-neighbours (a cheap test before joining)."""
    return any((a & b).any() for a, b in neighbours(mask))


def _touching_pairs(index: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the pairs of cells (their indices, -1 none) that are 8-neighbours, each once."""
    firsts, seconds = [], []
    for a, b in neighbours(index):
        both = (a >= 0) & (b >= 0)
        firsts.append(a[both])
        seconds.append(b[both])
    return np.concatenate(firsts), np.concatenate(seconds)


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


# a landmark picked by its distance from the robot, whose cell is not known
ROBOT_UNKNOWN = 'ambiguous: said of the robot, whose cell is not known'


def by_distance(d, name: str, anchor: str, pick: str):
    """
    Return (the index of the landmark nearest or farthest, None) or (None, why not).

    `d`: each landmark's distance from the anchor, centre to centre (Euclidean, as Janner's
    worlds say closest); `pick`: 'closest' or 'farthest'; a tie is declined.
    """
    d = np.asarray(d)
    best = d.min() if pick == 'closest' else d.max()
    ties = int(np.isclose(d, best).sum())
    if ties > 1:
        word = 'nearest' if pick == 'closest' else 'farthest'
        return None, f'ambiguous: {ties} {name}s tie as {word} from the {anchor}'
    return int(np.flatnonzero(np.isclose(d, best))[0]), None
