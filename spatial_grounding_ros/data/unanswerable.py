# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Generated instructions that no cell of their map answers, one kind of failure at a time.

Each case is a PuddleWorld-style world and an instruction in the generator's phrasing,
broken one way, with the reason a grounder should give (language/checks.py names them):

- `missing`: a landmark it names is not on the map (`referent-missing`);
- `unknown`: it names a landmark of no kind in the table (`unknown-landmark`);
- `off-map`: the cell it names lies past the map's edge (`off-map`);
- `ambiguous`: its one landmark is on the map several times (`ambiguous`);
- `obstacle`: the cell it names is a wall (`goal-on-obstacle`), on WALLED: PuddleWorld's table
  and a wall. A puddle is costly, not impassable: PuddleWorld's human data has goals in
  puddles, and a goal may lie in one (EntityTable.traversal);
- `unreachable`: the landmark it names is a box (solid: approached, never entered) walled in on
  every side, so no cell beside it can be reached (`unreachable`), on WALLED.
"""

from __future__ import annotations

import numpy as np

from .generator import FAMILY_OFFSETS, GRASS, random_grid, sample
from ..core.entities import (
    EntityTable,
    PUDDLEWORLD,
    PUDDLEWORLD_NAMES,
    PUDDLEWORLD_NONUNIQUE,
    PUDDLEWORLD_UNIQUE,
)
from ..language.lexicon import count_objects
from ..language.places import Landmark, Place, surface

# the reason each kind of case should be declined with
REASONS = {
    'missing': 'referent-missing',
    'unknown': 'unknown-landmark',
    'off-map': 'off-map',
    'ambiguous': 'ambiguous',
    'obstacle': 'goal-on-obstacle',
    'unreachable': 'unreachable',
}
KINDS = tuple(REASONS)
# PuddleWorld's table, a wall (impassable) and a box (solid): the model reads the wall as its
# obstacle (the puddle) and the box, named, as one of its landmarks, so it grounds these maps
# as PuddleWorld's
WALL, BOX = len(PUDDLEWORLD_NAMES), len(PUDDLEWORLD_NAMES) + 1
WALLED = EntityTable.from_dict({
    'domain': 'puddleworld-walled',
    'names': [*PUDDLEWORLD_NAMES, 'wall', 'box'],
    'traversal': {'grass': 'free', 'puddle': 'costly', 'wall': 'impassable', 'box': 'solid'},
    'footprints': False,
})
# the table of each kind of case that is not PuddleWorld's
TABLES = {'obstacle': WALLED, 'unreachable': WALLED}
# landmarks no PuddleWorld table holds, as a robot's user might name them
UNKNOWN_NAMES = (
    'fridge', 'sofa', 'lamp', 'door', 'chair', 'desk', 'window', 'sink', 'printer',
    'elevator', 'charger', 'shelf', 'plant', 'table', 'bench', 'fountain', 'statue', 'car',
)  # fmt: skip
_OFFSET_FAMILIES = ('two-step', 'far-step', 'combined', 'one-step')


def _unique_names(grid: np.ndarray) -> list[str]:
    return [n for n in PUDDLEWORLD_UNIQUE if (grid == PUDDLEWORLD.index(n)).sum() == 1]


def _offset_case(rng: np.random.Generator, size: int):
    """Return a world, an offset instruction from one unique object, the object and the goal."""
    while True:
        family = _OFFSET_FAMILIES[rng.integers(len(_OFFSET_FAMILIES))]
        grid, text, goal = sample(rng, family, size)
        name = next((n for n in PUDDLEWORLD_UNIQUE if text.endswith(f' {n}')), None)
        if name is not None:
            return grid, text, name, goal


def missing(rng: np.random.Generator, size: int):
    grid, text, name, _ = _offset_case(rng, size)
    grid[grid == PUDDLEWORLD.index(name)] = GRASS
    return grid, text


def unknown(rng: np.random.Generator, size: int):
    grid, text, name, _ = _offset_case(rng, size)
    return grid, text[: -len(name)] + UNKNOWN_NAMES[rng.integers(len(UNKNOWN_NAMES))]


def off_map(rng: np.random.Generator, size: int):
    """Return a world whose one object's named offset leaves the map from where it stands."""
    grid = random_grid(rng, size)
    offsets = FAMILY_OFFSETS['two-step'] + FAMILY_OFFSETS['far-step'] + FAMILY_OFFSETS['combined']
    dr, dc = offsets[rng.integers(len(offsets))]
    # a cell from which the offset leaves the map along one of its axes at least
    while True:
        r, c = int(rng.integers(0, size)), int(rng.integers(0, size))
        if not (0 <= r + dr < size and 0 <= c + dc < size):
            break
    name = PUDDLEWORLD_UNIQUE[rng.integers(len(PUDDLEWORLD_UNIQUE))]
    kind = PUDDLEWORLD.index(name)
    grid[grid == kind] = GRASS
    grid[r, c] = kind
    return grid, surface(Place('landmark', Landmark(name), (dr, dc)))


def ambiguous(rng: np.random.Generator, size: int):
    """Return a world whose non-unique object, named alone, fits the offset more than once."""
    grid = random_grid(rng, size)
    name = PUDDLEWORLD_NONUNIQUE[rng.integers(len(PUDDLEWORLD_NONUNIQUE))]
    kind = PUDDLEWORLD.index(name)
    offsets = [o for f in ('referent', 'one-step', 'two-step') for o in FAMILY_OFFSETS[f]]
    dr, dc = offsets[rng.integers(len(offsets))]
    inside = [
        (r, c)
        for r, c in zip(*np.nonzero(grid == kind))
        if 0 <= r + dr < size and 0 <= c + dc < size
    ]
    # two copies at least, apart (touching cells are one landmark), with the offset inside
    while len(inside) < 2 or count_objects(grid, kind) < 2:
        r, c = int(rng.integers(max(0, -dr), size - max(0, dr))), int(
            rng.integers(max(0, -dc), size - max(0, dc))
        )
        grid[r, c] = kind
        inside = [
            (r, c)
            for r, c in zip(*np.nonzero(grid == kind))
            if 0 <= r + dr < size and 0 <= c + dc < size
        ]
    return grid, surface(Place('landmark', Landmark(name), (dr, dc)))


def obstacle(rng: np.random.Generator, size: int):
    """Return an offset instruction whose named cell is a wall (WALLED's)."""
    grid, text, _, goal = _offset_case(rng, size)
    grid[goal] = WALL
    return grid, text


def unreachable(rng: np.random.Generator, size: int):
    """Return a world whose one box, named, has walls on all eight cells around it."""
    grid = random_grid(rng, size)
    r, c = (int(x) for x in rng.integers(1, size - 1, 2))
    grid[r - 1:r + 2, c - 1:c + 2] = WALL
    grid[r, c] = BOX
    return grid, ('reach cell with box', 'go to the box', 'reach the box')[rng.integers(3)]


MAKERS = {
    'missing': missing,
    'unknown': unknown,
    'off-map': off_map,
    'ambiguous': ambiguous,
    'obstacle': obstacle,
    'unreachable': unreachable,
}


def table_of(kind: str) -> EntityTable:
    """Return the entity table a kind of case's maps are of."""
    return TABLES.get(kind, PUDDLEWORLD)


def cases(kind: str, size: int, n: int, seed: int = 0) -> list[tuple[np.ndarray, str]]:
    """Return n (grid, instruction) of one kind and size; the same for every model."""
    if kind not in MAKERS:
        raise ValueError(f'unknown kind of case {kind!r}; use one of {", ".join(MAKERS)}')
    rng = np.random.default_rng([seed, size, KINDS.index(kind)])
    return [MAKERS[kind](rng, size) for _ in range(n)]
