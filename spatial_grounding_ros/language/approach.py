# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Approach goals: where a robot stops when it is sent to a landmark it cannot stand on.

"Go to the fridge", "go next to the sofa", "stop by the printer": a solid landmark
(EntityTable.solid: furniture) is never a goal cell; the goal is a cell beside its footprint
(its 8-connected cells of one kind, core/footprints.py). A cell is beside the footprint when
it shares an edge with one of its cells; its side (north, south, west, east) is the way it
lies from that cell. A robot may stop there when its kind is free or passable
(`stand`), and it gets there over cells that are not solid or impassable (`through`,
EntityTable.blocks_robot's complement), four-connected.

Which cell: with the robot's cell known, the one it reaches in the fewest steps (a
breadth-first search from its cell; the side cells it cannot reach are out); with none, a side
cell of the largest open region (the four-connected cells a robot may cross: the room, not a
pocket between the sofa and a wall; REGION_CAP cells or more count as equally large). Ties go
to the cell nearest the model's best cell, then to the first in row-major order. The
alternatives are the other sides, each at its best cell. No such cell: `unreachable`.

Plain Python and numpy: the grounder calls `approach_for` as one step after the model's best
cell is chosen.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from .checks import named_sides, nearness_alone
from .lexicon import Mention
from ..core.entities import EntityTable
from ..core.footprints import footprints

# the sides of a footprint, each the step from its cell to the cell beside it (row 0 north)
SIDES = {'north': (-1, 0), 'south': (1, 0), 'west': (0, -1), 'east': (0, 1)}
# an open region of this many cells counts as large as any (a 64x64 room): counting a whole
# large map's region cell by cell would cost more than the grounding
REGION_CAP = 4096

Cell = tuple[int, int]


@dataclass(frozen=True)
class Approach:
    """
    Where to stop beside a landmark: the goal, the landmark's cell it faces, the other sides.

    `goal` is None when no side cell can be reached (`reason` 'unreachable: fridge').
    """

    goal: Cell | None
    referent: Cell  # the footprint's cell nearest the goal (the best cell when none)
    others: tuple[Cell, ...]  # the best cell of each other side, best first
    reason: str | None = None


def footprint_of(grid: np.ndarray, kind: int, cell: Cell, drawn_over_cells: bool = True):
    """
    Return the footprint of `kind` that holds `cell`, or else its footprint nearest it.

    `drawn_over_cells` (EntityTable.has_footprints): if not, each cell is one landmark.
    """
    if drawn_over_cells:
        groups = footprints(grid, kind)
    else:
        groups = [np.array([c]) for c in np.argwhere(grid == kind)]
    return min(groups, key=lambda cells: float(((cells - np.asarray(cell)) ** 2).sum(1).min()))


def side_cells(footprint: np.ndarray, stand: np.ndarray) -> dict[str, list[Cell]]:
    """
    Return, per side, the cells beside a footprint where a robot may stop (`stand`).

    A cell beside the footprint on two sides (a notch of an L) counts for the first in SIDES.
    """
    h, w = stand.shape
    inside = {(int(r), int(c)) for r, c in footprint}
    out: dict[str, list[Cell]] = {}
    seen: set[Cell] = set()
    for side, (dr, dc) in SIDES.items():
        for r, c in sorted(inside):
            cell = (r + dr, c + dc)
            if cell in inside or cell in seen or not (0 <= cell[0] < h and 0 <= cell[1] < w):
                continue
            if stand[cell]:
                seen.add(cell)
                out.setdefault(side, []).append(cell)
    return out


def steps_from(through: np.ndarray, start: Cell, targets) -> dict[Cell, int]:
    """
    Return the fewest four-connected steps from `start` to each target it reaches.

    The walk crosses only `through` cells; the start counts whatever it is (the robot is
    there). It stops once every target is reached.
    """
    h, w = through.shape
    left = set(targets)
    found: dict[Cell, int] = {}
    seen = np.zeros(through.shape, dtype=bool)
    seen[start] = True
    todo = deque([(start, 0)])
    while todo and left:
        cell, n = todo.popleft()
        if cell in left:
            left.discard(cell)
            found[cell] = n
        r, c = cell
        for dr, dc in SIDES.values():
            nr, nc = r + dr, c + dc
            if 0 <= nr < h and 0 <= nc < w and through[nr, nc] and not seen[nr, nc]:
                seen[nr, nc] = True
                todo.append(((nr, nc), n + 1))
    return found


def region_sizes(through: np.ndarray, cells, cap: int = REGION_CAP) -> dict[Cell, int]:
    """Return, for each of `cells`, the size of its four-connected `through` region (<= cap)."""
    label = np.zeros(through.shape, dtype=np.int64)
    sizes = {}
    for cell in cells:
        if not label[cell]:
            region = len(sizes) + 1
            label[cell] = region
            todo, n = [cell], 0
            while todo and n < cap:
                r, c = todo.pop()
                n += 1
                for dr, dc in SIDES.values():
                    nr, nc = r + dr, c + dc
                    if (
                        0 <= nr < through.shape[0]
                        and 0 <= nc < through.shape[1]
                        and through[nr, nc]
                        and not label[nr, nc]
                    ):
                        label[nr, nc] = region
                        todo.append((nr, nc))
            sizes[region] = min(n, cap)
    return {cell: sizes[label[cell]] for cell in cells}


def approach(
    footprint: np.ndarray,
    stand: np.ndarray,
    through: np.ndarray,
    toward: Cell,
    robot_cell: Cell | None = None,
) -> tuple[Cell | None, Cell | None, tuple[Cell, ...]]:
    """
    Return the goal beside a footprint, the footprint's cell nearest it, and the other sides.

    `stand`, `through`: (H, W) masks of the cells a robot may stop on and cross; `toward`:
    the model's best cell; `robot_cell`: the robot's, or None (the module's rule). The goal is
    None when no side cell fits.
    """
    sides = side_cells(footprint, stand)
    cells = [cell for side in sides.values() for cell in side]
    if robot_cell is not None:
        rank = {cell: (n,) for cell, n in steps_from(through, robot_cell, cells).items()}
    else:
        rank = {cell: (-n,) for cell, n in region_sizes(through, cells).items()}

    def key(cell: Cell):
        return (*rank[cell], (cell[0] - toward[0]) ** 2 + (cell[1] - toward[1]) ** 2, cell)

    per_side = [[cell for cell in side if cell in rank] for side in sides.values()]
    best = sorted((min(side, key=key) for side in per_side if side), key=key)
    if not best:
        return None, None, ()
    goal = best[0]
    referent = footprint[((footprint - np.asarray(goal)) ** 2).sum(1).argmin()]
    return goal, (int(referent[0]), int(referent[1])), tuple(best[1:])


def approached_kind(
    table: EntityTable,
    grid: np.ndarray,
    words: list[str],
    mentions: list[Mention],
    best: Cell,
    offsets: list | None = None,
) -> int | None:
    """
    Return the solid landmark an instruction sends the robot to, or None.

    That is a named solid kind with no offset named from it ("go to the fridge", "the chair
    nearest the door") whose footprint the model's best cell is on, or the one solid kind
    named when nearness is all the words say of the goal ("go next to the sofa"). An offset
    from a solid landmark ("two cells below the sofa") is taken from its edge as before.
    `offsets`: the mentions' offsets as the reading has them (checks.map_reason).
    """
    solid = table.solid
    if not solid or not mentions:
        return None
    sides = named_sides(words, mentions, offsets)
    kind = int(grid[best])
    if kind in solid and sides.get(kind) == (0, 0):
        return kind
    kind = mentions[0].kind
    if kind in solid and nearness_alone(words, mentions):
        return kind
    return None


def checked_cell(grid: np.ndarray, cell) -> Cell:
    """Return a (row, col) of the grid as ints, or raise ValueError saying what is wrong."""
    try:
        r, c = (int(x) for x in cell)
    except (TypeError, ValueError) as exc:
        raise ValueError(f'robot_cell must be (row, col), got {cell!r}') from exc
    if not (0 <= r < grid.shape[0] and 0 <= c < grid.shape[1]):
        raise ValueError(f'robot_cell {(r, c)} is off the {grid.shape[0]}x{grid.shape[1]} map')
    return r, c


def approach_for(
    table: EntityTable,
    grid: np.ndarray,
    words: list[str],
    mentions: list[Mention],
    best: Cell,
    robot_cell: Cell | None = None,
    offsets: list | None = None,
) -> Approach | None:
    """
    Return where to stop when the instruction sends the robot to a solid landmark, or None.

    The grounder's approach step: None leaves the model's best cell the goal.
    """
    if robot_cell is not None:
        robot_cell = checked_cell(grid, robot_cell)
    kind = approached_kind(table, grid, words, mentions, best, offsets)
    if kind is None or not (grid == kind).any():  # a landmark not there: referent-missing
        return None
    footprint = footprint_of(grid, kind, best, table.has_footprints)
    stand = np.isin(grid, sorted(table.kinds_that_are('free', 'passable')))
    through = ~np.isin(grid, sorted(table.blocks_robot))
    goal, referent, others = approach(footprint, stand, through, best, robot_cell)
    if goal is None:
        nearest = footprint[((footprint - np.asarray(best)) ** 2).sum(1).argmin()]
        name = table.names[kind].replace('_', ' ')
        return Approach(None, (int(nearest[0]), int(nearest[1])), (), f'unreachable: {name}')
    return Approach(goal, referent, others)
