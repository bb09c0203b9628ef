"""Our own PuddleWorld-style worlds and synthetic instructions, so that everything (demo,
tests, the simulator) runs with no downloaded data.

Worlds follow Janner et al.'s layout: grass with puddle patches, each unique object
(star ... diamond) at most once, several non-unique ones (rock, tree, house, horse).
Instructions use their synthetic phrasing ("reach cell two below triangle", "reach
easternmost horse"), whose words all occur in the human PuddleWorld instructions too.
Row 0 is north: "above"/"top" is a smaller row index, "east"/"right" a larger column.
"""
from __future__ import annotations

import numpy as np

from . import world
from .datasets import GroundingSet
from .entities import PUDDLEWORLD, PUDDLEWORLD_NONUNIQUE, PUDDLEWORLD_UNIQUE

GRASS, PUDDLE = 0, 1
_NUMBER = {1: "one", 2: "two"}
_ONE_STEP = {(0, -1): "to left of", (0, 1): "to right of", (-1, 0): "on top of",
             (1, 0): "on bottom of", (-1, -1): "to top left of", (-1, 1): "to top right of",
             (1, -1): "to bottom left of", (1, 1): "to bottom right of"}
_TWO_STEP = {(-2, 0): "two above", (2, 0): "two below", (0, -2): "two to the left of",
             (0, 2): "two to the right of"}
# extreme -> (axis, sign): the object with the largest sign * coordinate on that axis
_EXTREMES = {"northernmost": (0, -1), "southernmost": (0, 1),
             "westernmost": (1, -1), "easternmost": (1, 1)}


def local_phrase(offset: tuple[int, int], name: str) -> str:
    """The instruction for the cell at `offset` (d_row, d_col) from an object."""
    dr, dc = offset
    if offset == (0, 0):
        return f"reach cell with {name}"
    if offset in _ONE_STEP:
        return f"reach cell {_ONE_STEP[offset]} {name}"
    if offset in _TWO_STEP:
        return f"reach cell {_TWO_STEP[offset]} {name}"
    horizontal = f"{_NUMBER[abs(dc)]} to the {'left' if dc < 0 else 'right'}"
    vertical = f"{_NUMBER[abs(dr)]} {'above' if dr < 0 else 'below'}"
    return f"reach cell {horizontal} and {vertical} {name}"


LOCAL_OFFSETS = [(0, 0), *_ONE_STEP, *_TWO_STEP,
                 *[(dr, dc) for dr in (-2, -1, 1, 2) for dc in (-2, -1, 1, 2)
                   if 2 in (abs(dr), abs(dc))]]


def random_grid(rng: np.random.Generator, size: int = 10, n_nonunique: int = 8) -> np.ndarray:
    """Grass, 1-3 rectangular puddles, unique objects (each at most once), non-unique ones."""
    grid = np.full((size, size), GRASS, dtype=np.int64)
    for _ in range(rng.integers(1, 4)):
        h, w = rng.integers(2, size // 2 + 1, size=2)
        r, c = rng.integers(0, size - h + 1), rng.integers(0, size - w + 1)
        grid[r:r + h, c:c + w] = PUDDLE
    free = np.flatnonzero(grid == GRASS)
    uniques = rng.choice(len(PUDDLEWORLD_UNIQUE), size=rng.integers(3, 7), replace=False)
    kinds = [PUDDLEWORLD.index(PUDDLEWORLD_UNIQUE[u]) for u in uniques]
    kinds += [PUDDLEWORLD.index(PUDDLEWORLD_NONUNIQUE[i])
              for i in rng.integers(0, len(PUDDLEWORLD_NONUNIQUE), size=n_nonunique)]
    cells = rng.choice(free, size=min(len(kinds), len(free)), replace=False)
    grid.reshape(-1)[cells] = kinds[:len(cells)]
    return grid


def local_goals(grid: np.ndarray) -> list[tuple[str, tuple[int, int]]]:
    """Every (instruction, goal) that names a unique object and an offset inside the map."""
    out = []
    h, w = grid.shape
    for name in PUDDLEWORLD_UNIQUE:
        where = np.argwhere(grid == PUDDLEWORLD.index(name))
        if len(where) != 1:
            continue
        r, c = where[0]
        for dr, dc in LOCAL_OFFSETS:
            if 0 <= r + dr < h and 0 <= c + dc < w:
                out.append((local_phrase((dr, dc), name), (int(r + dr), int(c + dc))))
    return out


def global_goals(grid: np.ndarray) -> list[tuple[str, tuple[int, int]]]:
    """Extremes ("reach northernmost rock") and nearest ("reach tree closest to star"),
    only where the answer is unique."""
    out = []
    for name in PUDDLEWORLD_NONUNIQUE:
        where = np.argwhere(grid == PUDDLEWORLD.index(name))
        if len(where) < 2:
            continue
        for word, (axis, sign) in _EXTREMES.items():
            key = sign * where[:, axis]
            if (key == key.max()).sum() == 1:
                out.append((f"reach {word} {name}", tuple(int(x) for x in where[key.argmax()])))
        for ref in PUDDLEWORLD_UNIQUE:
            anchor = np.argwhere(grid == PUDDLEWORLD.index(ref))
            if len(anchor) != 1:
                continue
            dist = np.abs(where - anchor[0]).sum(axis=1)
            if (dist == dist.min()).sum() == 1:
                out.append((f"reach {name} closest to {ref}",
                            tuple(int(x) for x in where[dist.argmin()])))
    return out


def generate(n: int, seed: int = 0, mode: str = "local", size: int = 10) -> GroundingSet:
    """`n` examples, each a fresh world with one instruction, its goal and true value map."""
    if mode not in ("local", "global", "mixed"):
        raise ValueError(f"unknown generator mode {mode!r}; use local, global or mixed")
    if size < 5:
        raise ValueError(f"generated worlds need size >= 5, not {size}")
    rng = np.random.default_rng(seed)
    rows = []
    while len(rows) < n:
        grid = random_grid(rng, size)
        use_local = mode == "local" or (mode == "mixed" and rng.random() < 0.5)
        goals = local_goals(grid) if use_local else global_goals(grid)
        if not goals:
            continue
        text, goal = goals[rng.integers(len(goals))]
        rows.append((grid, text, goal, f"generated/{seed}/{len(rows)}"))
    grids = np.stack([r[0] for r in rows])
    rewards, terminal = map(np.stack, zip(*(world.reward_map(g == PUDDLE, r[2])
                                            for g, r in zip(grids, rows))))
    values = world.value_iteration(rewards, terminal)
    return GroundingSet(f"generated-{mode}-{seed}", PUDDLEWORLD, grids, [r[1] for r in rows],
                        values.astype(np.float32), rewards.astype(np.float32), terminal,
                        np.array([r[2] for r in rows], dtype=np.int64), [r[3] for r in rows])
