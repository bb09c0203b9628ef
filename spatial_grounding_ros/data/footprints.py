# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Generated worlds as a robot's map draws them: landmarks over several cells, unexplored regions.

In a table whose landmarks have footprints (EntityTable.has_footprints) touching cells of one
kind are one landmark, so `separate` first leaves one cell of each touching group: the
answer's own landmark (taking away any other keeps a unique extreme or closest answer
unique). `grow` then draws landmarks over rectangles of 1-3 by 1-3
cells, placed so that the cell they were is the footprint's anchor for the side the
instruction's offset leaves them on (core/footprints.py): the goal stays the cell named.
`unexplored` covers free cells with rectangles of the table's unknown kind, never the goal.
"""

from __future__ import annotations

import numpy as np

from ..core.entities import EntityTable
from ..core.footprints import footprints
from ..core.text import tokenize
from ..language.checks import mention_offsets, named_sides
from ..language.lexicon import COMMON_WORDS, Lexicon

GROW_SHARE = 0.7  # the share of landmarks drawn over more than one cell
LARGEST = 3  # a footprint's longest side, in cells


def unknown_kind(table: EntityTable) -> int:
    """Return the kind a table gives unexplored cells: 'unknown', or its last obstacle."""
    if 'unknown' in table.names:
        return table.index('unknown')
    if not table.obstacles:
        raise ValueError(f'the {table.domain} table has no obstacle kind for unexplored cells')
    return table.obstacles[-1]


def mentions_of(words: list[str], table: EntityTable):
    """Return the landmarks the words name, read as the Grounder reads them."""
    return Lexicon(table, COMMON_WORDS).mentions(words)


def separate(
    grid: np.ndarray, instruction: str, goal: tuple[int, int], table: EntityTable
) -> np.ndarray:
    """
    Return the grid with one cell of each touching group of a landmark kind kept.

    A group keeps the landmark the answer is taken from (the goal less a named offset), else
    the goal's own, else the cell nearest the goal: taking away any other landmark keeps a
    unique extreme or closest answer unique.
    """
    words = tokenize(instruction)
    offsets = mention_offsets(words, mentions_of(words, table))
    referents = [(goal[0] - dr, goal[1] - dc) for _, (dr, dc) in offsets]
    out = grid.copy()
    free = table.free_kind
    for kind in np.unique(grid):
        if kind in table.obstacles or kind == free:
            continue
        for cells in footprints(grid, int(kind)):
            if len(cells) < 2:
                continue
            listed = [tuple(c) for c in cells.tolist()]
            keep = next(
                (listed.index(c) for c in [*referents, tuple(goal)] if c in listed),
                int(np.abs(cells - np.asarray(goal)).sum(1).argmin()),
            )
            gone = np.delete(cells, keep, axis=0)
            out[gone[:, 0], gone[:, 1]] = free
    return out


def _rows(at: int, side: int, n: int) -> range:
    """Return the n rows (or columns) whose anchor on `side` is `at`."""
    if side > 0:
        return range(at - n + 1, at + 1)
    if side < 0:
        return range(at, at + n)
    return range(at - (n - 1) // 2, at + n // 2 + 1)


def grow(
    grid: np.ndarray,
    instruction: str,
    goal: tuple[int, int],
    table: EntityTable,
    rng: np.random.Generator,
) -> np.ndarray:
    """Return the grid with its landmarks drawn over footprints that keep the goal named."""
    words = tokenize(instruction)
    sides = named_sides(words, mentions_of(words, table))
    out = grid.copy()
    free = table.free_kind
    h, w = grid.shape
    for r, c in np.argwhere((grid != free) & ~np.isin(grid, table.obstacles)):
        if rng.random() >= GROW_SHARE:
            continue
        kind = int(grid[r, c])
        side = sides.get(kind, (0, 0))
        size = rng.integers(1, LARGEST + 1, size=2)
        rows, cols = _rows(r, side[0], int(size[0])), _rows(c, side[1], int(size[1]))
        if rows.start < 0 or cols.start < 0 or rows.stop > h or cols.stop > w:
            continue
        block = out[rows.start:rows.stop, cols.start:cols.stop]
        others = out == kind
        others[r, c] = False
        near = np.zeros_like(others)  # cells touching another landmark of the kind
        padded = np.pad(others, 1)
        for dr in (0, 1, 2):
            for dc in (0, 1, 2):
                near |= padded[dr:dr + h, dc:dc + w]
        inside_goal = rows.start <= goal[0] < rows.stop and cols.start <= goal[1] < cols.stop
        mine = (block == free) | (block == kind)
        if inside_goal or not mine.all() or near[rows.start:rows.stop, cols.start:cols.stop].any():
            continue
        block[...] = kind
    return out


def unexplored(
    grid: np.ndarray, goal: tuple[int, int], table: EntityTable, rng: np.random.Generator
) -> np.ndarray:
    """Return the grid with 1-3 rectangles of free cells (never the goal) made unknown."""
    out = grid.copy()
    free, unknown = table.free_kind, unknown_kind(table)
    h, w = grid.shape
    for _ in range(int(rng.integers(1, 4))):
        rh, rw = (int(x) for x in rng.integers(2, max(3, min(h, w) // 3 + 1), size=2))
        r, c = int(rng.integers(0, h - rh + 1)), int(rng.integers(0, w - rw + 1))
        block = out[r:r + rh, c:c + rw]
        block[block == free] = unknown
    out[goal] = grid[goal]
    return out
