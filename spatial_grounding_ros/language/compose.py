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

from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from .places import Landmark, ORDINAL_WORDS, PICKED, Place, ROBOT, side_words, SIDES
from ..core.entities import EntityTable
from ..core.footprints import anchor, by_distance, footprints, ROBOT_UNKNOWN, side_of

Cell = tuple[int, int]
# the network's grounding of a place it learned: (value map, its aux, its words, the rest of
# the offset to shift the map by); and the grounder's judge: (best cell, confidence, others)
Network = Callable[[Place], tuple]
Judge = Callable[[np.ndarray], tuple]
# a midpoint half a cell off is taken on maps whose half cell is at most this (metres): Nav2's
# default goal tolerance (xy_goal_tolerance), so the robot cannot tell the two middle cells apart
EVEN_GAP_TOLERANCE_M = 0.25


@dataclass
class Composed:
    """
    A composed place: its cells and how sure, or a shift of the network's value map.

    `cells`: [(cell, share)], none when declined; `values`: the network's value map, shifted;
    `landmark_cell`: the place is that landmark's own cell.
    """

    cells: list = field(default_factory=list)
    confidence: float = 0.0
    reason: str | None = None
    words: list = field(default_factory=list)
    values: np.ndarray | None = None
    aux: dict | None = None
    landmark_cell: Cell | None = None


def compose(
    place: Place, table: EntityTable, grid: np.ndarray, kinds: dict[str, int],
    reason: str | None, network: Network, judge: Judge, robot_cell: Cell | None = None,
    cell_size: float | None = None,
) -> Composed:
    """
    Return a composed place's cells from the network's groundings of its landmarks.

    An offset past the learned ones shifts the network's value map of the learned part
    (places.learned_part); between is the midpoint of its two landmarks; an ordinal or a
    farthest picks among the map's landmarks of the kind; a corner or a side is the map's.
    `kinds`: each landmark name's kind; `reason`: why the reading already declines, or None;
    `robot_cell`: the robot's (row, col), if known (the anchor of "the nearest chair");
    `cell_size`: metres per cell, if known (a midpoint's tolerance).
    """
    for name, kind in kinds.items():
        if reason is None and kind not in table.obstacles and not (grid == kind).any():
            reason = f'referent-missing: {name.replace("_", " ")}'
    if reason is not None:
        return Composed(reason=reason)
    if place.relation in ('corner', 'edge'):
        cells, reason = map_place(table, grid, place)
        return Composed(cells, 1.0, reason)
    if place.relation == 'robot':  # "and come back": where it is now
        if robot_cell is None:
            return Composed(reason='ambiguous: "back" is where the robot is now, and its cell is '
                            'not known')
        return Composed([(tuple(robot_cell), 1.0)], 1.0)
    locate = Locator(table, grid, kinds, network, judge, robot_cell)
    if place.relation in ('between', 'both'):
        (a, pa, wa, ra), (b, pb, wb, rb) = map(locate.candidates, (place.landmark, place.other))
        cell, reason = (None, ra or rb) if ra or rb else between(place, a, b, grid, kinds,
                                                                 cell_size)
        return Composed([] if cell is None else [(cell, 1.0)], pa * pb, reason, wa + wb)
    if place.relation == 'row-col':  # past the learned counts: one's row, the other's column
        (a, pa, wa, ra), (b, pb, wb, rb) = locate(place.landmark), locate(place.other)
        if ra or rb:
            return Composed([], pa * pb, ra or rb, wa + wb)
        o, p = place.offset, place.other_offset
        dr, dc = o[0] + p[0], o[1] + p[1]
        row = anchor(a if o[0] else b, side_of((dr, 0)))[0]  # of the landmark the row is said of
        col = anchor(a if o[1] else b, side_of((0, dc)))[1]
        goal = (row + dr, col + dc)
        reason = None if inside(grid, goal) else 'off-map'
        return Composed([] if reason else [(goal, 1.0)], pa * pb, reason, wa + wb)
    landmark, offset = place.landmark, place.offset
    if landmark.pick not in PICKED:  # the network's landmark, shifted
        found = instances(grid, kinds[landmark.name], table.has_footprints)
        name = landmark.name.replace('_', ' ')
        if landmark.pick is None and len(found) > 1:
            return Composed(reason=f'ambiguous: {len(found)} {name}s')
        if landmark.pick == 'extreme':  # two that share the extreme: no one landmark
            _, reason = ordinal(found, replace(landmark, rank=1), name)
            if reason is not None:
                return Composed(reason=reason)
        values, aux, words, rest = network(place)
        first, _, _ = judge(values)
        target = (first[0] + rest[0], first[1] + rest[1])
        return Composed(reason=None if inside(grid, target) else 'off-map', words=words,
                        values=shifted(values, rest), aux=aux)
    cells, confidence, words, reason = locate(landmark)
    if reason is not None:
        return Composed([], confidence, reason, words)
    if offset == (0, 0):  # the landmark itself: beside it, if it is solid
        near = np.abs(cells - centre(cells)).sum(1).argmin()
        cell = (int(cells[near][0]), int(cells[near][1]))
        return Composed([(cell, 1.0)], confidence, None, words, landmark_cell=cell)
    base = anchor(cells, side_of(offset))
    goal = (base[0] + offset[0], base[1] + offset[1])
    if not inside(grid, goal):
        return Composed([], confidence, 'off-map', words)
    return Composed([(goal, 1.0)], confidence, None, words)


class Locator:
    """Find one landmark of a place: (its cells, confidence, network words, reason)."""

    def __init__(self, table, grid, kinds, network: Network, judge: Judge, robot_cell=None):
        self.table, self.grid, self.kinds = table, grid, kinds
        self.network, self.judge, self.robot_cell = network, judge, robot_cell

    def __call__(self, landmark: Landmark):
        """
        Return the landmark's cells, how sure, the network's words and None, or why not.

        The network grounds a landmark said as it learned it ("reach westernmost rock"); an
        ordinal, a closest or a farthest picks among the kind's landmarks on the map (the
        nearest or farthest from its anchor, as the network grounds that).
        """
        found = instances(self.grid, self.kinds[landmark.name], self.table.has_footprints)
        name = landmark.name.replace('_', ' ')
        if landmark.pick == 'ordinal':
            i, reason = ordinal(found, landmark, name)
            return (None if i is None else found[i]), 1.0, [], reason
        if landmark.pick == 'closest' and landmark.anchor.name == ROBOT and len(found) == 1:
            return found[0], 1.0, [], None  # the only one is the nearest, wherever the robot is
        if landmark.pick == 'closest' or landmark.pick == 'farthest':
            anchors, confidence, words, reason = self.candidates(landmark.anchor)
            if reason is None and len(anchors) > 1 and landmark.pick == 'farthest':
                reason = f'ambiguous: {len(anchors)} {landmark.anchor.name.replace("_", " ")}s'
            if reason is not None:
                return None, confidence, words, reason
            anchor = landmark.anchor.name.replace('_', ' ')
            # of several anchors ("the rock next to the house"), the landmark nearest any
            d = nearest_distances(centres(found), centres(anchors))
            i, reason = by_distance(d, name, anchor, landmark.pick)
            return (None if i is None else found[i]), confidence, words, reason
        if landmark.pick == 'beside':
            return self.beside(landmark, found, name)
        if landmark.pick is None and len(found) > 1:
            return None, 1.0, [], f'ambiguous: {len(found)} {name}s'
        values, _, words, _ = self.network(Place('landmark', landmark))
        best, confidence, _ = self.judge(values)
        return found[nearest_to(found, best)], confidence, words, None

    def beside(self, landmark: Landmark, found: list, name: str):
        """
        Locate "the heart left of the horse": of the kind's landmarks on that side, the nearest.

        On that side: centre against centre, beyond the anchor along each axis the side names.
        None there is no such landmark (declined), two as near a tie.
        """
        anchors, confidence, words, reason = self.candidates(landmark.anchor)
        if reason is not None:
            return None, confidence, words, reason
        anchor = landmark.anchor.name.replace('_', ' ')
        step = np.sum([SIDES[s] for s in landmark.side.split('-')], 0)  # 'north-west': (-1, -1)
        gaps = centres(found)[:, None] - centres(anchors)[None]  # (landmark, anchor, 2)
        # on that side: beyond the anchor along each axis the side names (above: any column)
        ahead = ((gaps * step > 0) | (step == 0)).all(-1)
        # its distance from the cell `rank` steps that way from the nearest anchor it lies on
        # the side of ("the house 5 above the horse"; no count: one step)
        off = gaps - landmark.rank * step
        d = np.where(ahead, np.hypot(off[..., 0], off[..., 1]), np.inf).min(1)
        if np.isinf(d).all():
            side = {'north': 'above', 'south': 'below'}.get(landmark.side, f'{landmark.side} of')
            return None, confidence, words, f'referent-missing: no {name} {side} the {anchor}'
        i, reason = by_distance(d, name, anchor, 'closest')
        return (None if i is None else found[i]), confidence, words, reason

    def candidates(self, landmark: Landmark):
        """
        Return ([each landmark it may be], confidence, words, reason).

        A kind said alone ("the rock" of several) may be any of its landmarks; the relation
        then picks.
        """
        if landmark.name == ROBOT:
            if self.robot_cell is None:
                return [], 1.0, [], ROBOT_UNKNOWN
            return [np.array([self.robot_cell])], 1.0, [], None
        found = instances(self.grid, self.kinds[landmark.name], self.table.has_footprints)
        if landmark.pick is None and len(found) > 1:
            return found, 1.0, [], None
        cells, confidence, words, reason = self(landmark)
        return [cells], confidence, words, reason


def inside(grid: np.ndarray, cell: Cell) -> bool:
    """Say whether a (row, col) is a cell of the grid."""
    return 0 <= cell[0] < grid.shape[0] and 0 <= cell[1] < grid.shape[1]


def shifted(values: np.ndarray, offset: tuple[int, int]) -> np.ndarray:
    """Return a value map moved by (rows, cols), the cells it leaves at its lowest value."""
    if offset == (0, 0):
        return values
    out = np.full_like(values, values.min())
    h, w = values.shape
    dr, dc = offset
    if abs(dr) < h and abs(dc) < w:
        out[max(dr, 0):h + min(dr, 0), max(dc, 0):w + min(dc, 0)] = values[
            max(-dr, 0):h + min(-dr, 0), max(-dc, 0):w + min(-dc, 0)
        ]
    return out


_FROM = {'north': 'the top', 'south': 'the bottom', 'west': 'the left', 'east': 'the right'}


def plain_row_col(place: Place, table: EntityTable, grid: np.ndarray, mentions) -> bool:
    """
    Say whether a row-col place names two landmarks the map holds once each, plainly.

    Its cell is then one's row and the other's column, whatever the counts: composed, as
    the network missed it on maps unlike its training ones ("one above the fridge and two
    left of the sofa"). With a landmark held twice the network picks one, as the PuddleWorld
    annotators meant it more often than not: declining it lost 22 of their right answers.
    """
    if place.relation != 'row-col' or place.landmark.pick or place.other.pick:
        return False
    kinds = {m.kind for m in mentions}
    return len(kinds) == 2 and all(
        len(instances(grid, k, table.has_footprints)) == 1 for k in kinds
    )


def instances(grid: np.ndarray, kind: int, drawn_over_cells: bool) -> list[np.ndarray]:
    """Return each landmark of a kind: its footprint, or each cell when a table has none."""
    if drawn_over_cells:
        return sorted(footprints(grid, kind), key=lambda f: tuple(f.min(0)))
    return [cell[None] for cell in np.argwhere(grid == kind)]


def centre(cells: np.ndarray) -> np.ndarray:
    """Return a landmark's centre: the mean of its cells (row, col)."""
    return cells.mean(0)


def centres(landmarks: list[np.ndarray]) -> np.ndarray:
    """Return each landmark's centre as (N, 2): a landmark of one cell is that cell."""
    if all(len(cells) == 1 for cells in landmarks):
        return np.concatenate(landmarks).astype(np.float64)
    return np.array([centre(cells) for cells in landmarks])


def nearest_to(landmarks: list[np.ndarray], cell: Cell) -> int:
    """Return the index of the landmark with a cell nearest `cell` (the first of equals)."""
    if all(len(cells) == 1 for cells in landmarks):
        return int(((np.concatenate(landmarks) - np.asarray(cell)) ** 2).sum(1).argmin())
    return int(np.argmin([((c - np.asarray(cell)) ** 2).sum(1).min() for c in landmarks]))


def nearest_distances(points: np.ndarray, anchors: np.ndarray, pairs: int = 1 << 20):
    """Return each point's distance to its nearest anchor (Euclidean), `pairs` at a time."""
    out = np.empty(len(points))
    step = max(1, pairs // max(1, len(anchors)))
    for start in range(0, len(points), step):
        d = points[start:start + step, None] - anchors[None]
        out[start:start + step] = np.hypot(d[..., 0], d[..., 1]).min(1)
    return out


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


def between(place: Place, a: list, b: list, grid: np.ndarray, kinds: dict, cell_size=None):
    """
    Return (the cell of a between or a both place, None), or (None, why not).

    `a`, `b`: the landmarks each may be (Locator.candidates). Said by sides ("below the tree and
    above the horse"), the one cell at those sides of both, else (not for counts) the midpoint
    if it lies on both sides; of two of a kind ("between the two chairs"), the map's two.
    """
    names = (place.landmark.name, place.other.name)
    said = None
    if place.offset != (0, 0):
        counted = place.relation == 'both'
        said = (f'{side_words(place.offset, counted)} a {names[0]} and '
                f'{side_words(place.other_offset, counted)} a {names[1]}')
        met = meeting(a, place.offset, b, place.other_offset, grid)
        if len(met) == 1:
            return met[0], None
        if met:
            return None, f'ambiguous: {len(met)} cells are {said}'
        if counted:
            return None, f'ambiguous: no cell is {said}'
    if place.landmark == place.other:  # two of the same landmarks
        n, b = len(a), a
        if n < 2 or n > 2 and place.on is None:  # ("the house between two trees": any two)
            return None, f'ambiguous: {n} {names[0]}{"s" * (n != 1)} on the map, not two'
    on = None if place.on is None else kinds.get(place.on)
    a, b, reason = closest_pair(a, b, grid, on, names)
    if reason is not None:
        return None, reason
    cell, reason = midpoint(a, b, names, cell_size)
    if cell is not None and said and not (
        on_side(cell, a, place.offset) and on_side(cell, b, place.other_offset)
    ):
        return None, f'ambiguous: no cell is {said}'
    return cell, reason


def closest_pair(a: list, b: list, grid: np.ndarray, on: int | None, names: tuple[str, str]):
    """
    Return (a landmark of each, None) for a between, or (None, None, why not).

    Of several of a kind ("between the tree and the rock"), the pair nearest each other; with
    a landmark named on the goal ("the horse between the circle and the tree"), the pairs whose
    middle holds it first. A tie is declined.
    """
    # of one list (two of a kind), each pair once
    pairs = [(x, y) for i, x in enumerate(a) for j, y in enumerate(b)
             if x is not y and (a is not b or i < j)]
    if on is not None:
        holding = [(x, y) for x, y in pairs if _middle_holds(x, y, grid, on, names)]
        pairs = holding or pairs
    d = np.array([np.hypot(*(centre(x) - centre(y))) for x, y in pairs])
    if int(np.isclose(d, d.min()).sum()) > 1:
        return None, None, f'ambiguous: which {names[0]} and {names[1]} is not said'
    return (*pairs[int(d.argmin())], None)


def _middle_holds(x, y, grid, kind, names) -> bool:
    cell, _ = midpoint(x, y, names)
    return cell is not None and int(grid[cell]) == kind


def on_side(cell: tuple[int, int], landmark: np.ndarray, side: tuple[int, int]) -> bool:
    """Say whether a cell lies past a landmark's cells on a side ((0, -1): west; (0, 0): any)."""
    for axis in (0, 1):
        if side[axis] < 0 and not cell[axis] < landmark[:, axis].min():
            return False
        if side[axis] > 0 and not cell[axis] > landmark[:, axis].max():
            return False
    return True


def meeting(a: list, side_a, b: list, side_b, grid: np.ndarray) -> list:
    """Return the cells at `side_a` from a landmark of `a` and at `side_b` from one of `b`."""
    def steps(found, offset):
        return {(int(r) + offset[0], int(c) + offset[1]) for x in found for r, c in x
                if on_side((r + offset[0], c + offset[1]), x, offset)}
    return [c for c in sorted(steps(a, side_a) & steps(b, side_b)) if inside(grid, c)]


def midpoint(a: np.ndarray, b: np.ndarray, names: tuple[str, str], cell_size=None):
    """
    Return (the cell halfway between two landmarks, None) or (None, why not).

    On each axis, halfway between their facing edges (of one-cell landmarks, their cells); where
    their extents overlap, the middle of the overlap. An even gap has no middle cell: on a map
    whose half cell is within EVEN_GAP_TOLERANCE_M (`cell_size`, metres per cell) the middle
    cell nearer `a` is taken; on others (PuddleWorld's, without a size) it declines.
    """
    mid = []
    for axis in (0, 1):
        (lo_a, hi_a), (lo_b, hi_b) = (
            (int(c[:, axis].min()), int(c[:, axis].max())) for c in (a, b)
        )
        if hi_a < lo_b:
            mid.append((hi_a + lo_b) / 2)
        elif hi_b < lo_a:
            mid.append((hi_b + lo_a) / 2)
        else:  # side by side on this axis: the middle of the rows (columns) both span
            mid.append((max(lo_a, lo_b) + min(hi_a, hi_b)) / 2)
    mid = np.asarray(mid)
    if cell_size is not None and cell_size / 2 <= EVEN_GAP_TOLERANCE_M:
        towards_a = centre(a) < mid  # a half cell: round towards a
        mid = np.where(np.isclose(mid % 1, 0.5), np.where(towards_a, mid - 0.5, mid + 0.5), mid)
    if not np.allclose(mid, np.round(mid)):
        return None, (
            f'ambiguous: halfway between the {names[0]} and the {names[1]} falls between cells '
            '(an even gap)'
        )
    return (int(round(mid[0])), int(round(mid[1]))), None


def map_place(table: EntityTable, grid: np.ndarray, place: Place):
    """
    Return ([(cell, share)], None) for a corner or a side's middle, or ([], why not).

    The room is the box of the floor (free or costly cells: inside the walls of a robot's map,
    all of a PuddleWorld map); its corner, or its side's middle cell (of an even side, both
    middle cells, each half), is the point. The goal is the point where a robot may stop
    there (the floor first, then a landmark it may stand on), else the floor cell nearest it.
    A point the map has not seen is declined.
    """
    floor = np.isin(grid, sorted(table.kinds_that_are('free', 'costly')))
    if not floor.any():
        return [], 'unreachable: no floor on the map to stop on'
    rows, cols = np.flatnonzero(floor.any(1)), np.flatnonzero(floor.any(0))
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
    unknown = [k for k, n in enumerate(table.names) if n == 'unknown']
    if any(int(grid[p]) in unknown for p in points):
        return [], f'unknown-region: {said} of the map is not mapped'
    stand = ~np.isin(grid, sorted(table.never_goal | table.blocks_robot))
    for where in (floor, stand):  # of two middle cells, the one a robot may stop on
        found = [p for p in points if where[p]]
        if found:
            return [((int(r), int(c)), 1 / len(found)) for r, c in found], None
    cells = np.argwhere(floor)
    d = np.min([((cells - np.asarray(p)) ** 2).sum(1) for p in points], 0)
    return [((int(r), int(c)), 1.0) for r, c in cells[d == d.min()][:1]], None


def cell_values(cells, shape) -> np.ndarray:
    """Return a composed place's value map: each cell its share, every other cell 0."""
    values = np.zeros(shape, dtype=np.float32)
    for cell, share in cells:
        values[cell] = share
    return values


def renamed(place: Place, names: dict[str, str]) -> Place:
    """Return a place with each landmark named by `names` (the table's name -> the network's)."""

    def one(lm):
        if lm is None:
            return None
        return replace(lm, name=names.get(lm.name, lm.name), anchor=one(lm.anchor))

    return replace(place, landmark=one(place.landmark), other=one(place.other),
                   on=None if place.on is None else names.get(place.on, place.on))
