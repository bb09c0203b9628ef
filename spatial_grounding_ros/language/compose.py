# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The geometry of the places the network does not ground whole (places.composed).

The grounder grounds each landmark of such a place with the network, then one of these picks
the cell: the k-th landmark of a kind from a side (`ordinal`), the one farthest from another
(`farthest`), the midpoint of two (`midpoint`), a corner or the middle of a side of the mapped
area (`map_place`). Each says why when no one cell fits: a tie, an even gap, a corner in an
unmapped region. Plain numpy: a landmark is its cells ((n, 2) arrays of (row, col)).
"""

from __future__ import annotations

import numpy as np

from .places import Landmark, ORDINAL_WORDS, Place, SIDES
from ..core.entities import EntityTable
from ..core.footprints import footprints

Cell = tuple[int, int]
_FROM = {'north': 'the top', 'south': 'the bottom', 'west': 'the left', 'east': 'the right'}


def instances(grid: np.ndarray, kind: int, drawn_over_cells: bool) -> list[np.ndarray]:
    """Return each landmark of a kind: its footprint, or each cell when a table has none."""
    if drawn_over_cells:
        return sorted(footprints(grid, kind), key=lambda f: tuple(f.min(0)))
    return [cell[None] for cell in np.argwhere(grid == kind)]


def centre(cells: np.ndarray) -> np.ndarray:
    """Return a landmark's centre: the mean of its cells (row, col)."""
    return cells.mean(0)


def edge_key(cells: np.ndarray, side: str) -> int:
    """Return how far a landmark is from `side` (its nearest cell's row or column): 0 is first."""
    axis, sign = (0, SIDES[side][0]) if SIDES[side][0] else (1, SIDES[side][1])
    return int(-sign * (cells[:, axis].max() if sign > 0 else cells[:, axis].min()))


def ordinal(found: list[np.ndarray], landmark: Landmark, name: str):
    """Return (the index of the rank-th landmark from its side, None) or (None, why not)."""
    k = landmark.rank
    keys = sorted(edge_key(cells, landmark.side) for cells in found)
    said = f'{ORDINAL_WORDS.get(k, k)} {name} from {_FROM[landmark.side]}'
    if len(found) < k:
        return None, f'referent-missing: no {said} ({len(found)} on the map)'
    key = keys[k - 1]
    if keys.count(key) > 1:
        return None, f'ambiguous: {keys.count(key)} {name}s tie as the {said}'
    return [edge_key(c, landmark.side) for c in found].index(key), None


def farthest(found: list[np.ndarray], point: np.ndarray, name: str, anchor: str):
    """Return (the index of the landmark farthest from `point`, None) or (None, why not)."""
    if len(found) < 2:
        return None, f'ambiguous: {len(found)} {name} on the map, none farther than another'
    d = np.array([np.hypot(*(centre(c) - point)) for c in found])
    ties = int(np.isclose(d, d.max()).sum())
    if ties > 1:
        return None, f'ambiguous: {ties} {name}s tie as farthest from the {anchor}'
    return int(d.argmax()), None


def midpoint(a: np.ndarray, b: np.ndarray, names: tuple[str, str]):
    """Return (the cell halfway between two landmarks, None) or (None, why not)."""
    mid = (centre(a) + centre(b)) / 2
    if not np.allclose(mid, np.round(mid)):
        return None, (
            f'ambiguous: halfway between the {names[0]} and the {names[1]} falls between cells '
            '(an even gap)'
        )
    return (int(round(mid[0])), int(round(mid[1]))), None


def map_place(table: EntityTable, grid: np.ndarray, place: Place):
    """
    Return ([(cell, share)], None) for a corner or a side's middle, or ([], why not).

    The mapped area is the box of the cells that are not unknown; its corner (or its side's
    middle cell: of an even side, both middle cells, each half) is the point; the goal the
    cell nearest it a robot may stop on. A point in unmapped space is declined.
    """
    unknown = [k for k, n in enumerate(table.names) if n == 'unknown']
    known = ~np.isin(grid, unknown)
    if not known.any():
        return [], 'unknown-region: nothing of the map is mapped'
    rows, cols = np.flatnonzero(known.any(1)), np.flatnonzero(known.any(0))
    r0, r1, c0, c1 = rows[0], rows[-1], cols[0], cols[-1]
    if place.relation == 'corner':
        vertical, horizontal = place.side.split('-')
        points = [(r0 if vertical == 'north' else r1, c0 if horizontal == 'west' else c1)]
        said = f'the {place.side} corner'
    else:
        dr, dc = SIDES[place.side]
        lo, hi = (c0, c1) if dr else (r0, r1)
        middles = sorted({(lo + hi) // 2, (lo + hi + 1) // 2})
        fixed = (r0 if dr < 0 else r1) if dr else (c0 if dc < 0 else c1)
        points = [(fixed, m) if dr else (m, fixed) for m in middles]
        said = f'the middle of the {place.side} side'
    stand = known & ~np.isin(grid, sorted(table.never_goal | table.blocks_robot))
    if not stand.any():
        return [], 'unreachable: no cell of the map to stop on'
    out = []
    for point in points:
        if not known[point]:
            return [], f'unknown-region: {said} of the map is not mapped'
        where = np.argwhere(stand)
        cell = where[((where - np.asarray(point)) ** 2).sum(1).argmin()]
        out.append(((int(cell[0]), int(cell[1])), 1 / len(points)))
    return out, None
