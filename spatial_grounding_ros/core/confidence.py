# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
A value map read as calibrated chances: the softmax of its values at a temperature.

The temperature is the checkpoint's (studies/calibration.py fits it); every chance the
Grounder reports, and the certainty that decides its mirror averaging, is read here.
"""

from __future__ import annotations

import numpy as np

from .footprints import footprints

# how many next-best cells a grounding reports
ALTERNATIVES = 3


def judged(values: np.ndarray, temperature: float):
    """Return the best cell, its calibrated probability, and the next best with theirs."""
    flat = values.reshape(-1).astype(np.float64) / temperature
    p = np.exp(flat - flat.max())
    p /= p.sum()
    best = int(np.argmax(flat))  # the first of equal maxima, as numpy's argmax
    k = min(ALTERNATIVES + 1, p.size)
    top = np.argpartition(-p, k - 1)[:k]
    others = [i for i in top[np.argsort(-p[top], kind='stable')] if i != best][:ALTERNATIVES]

    def cell(i):  # a flat index's (row, col): divmod, unravel_index's cost is per call
        return divmod(int(i), values.shape[1])

    return cell(best), float(p[best]), [(cell(i), float(p[i])) for i in others]


def certainty(values: np.ndarray, temperature: float) -> float:
    """Return the calibrated probability of the best cell, as judged() gives it."""
    flat = values.reshape(-1).astype(np.float64) / temperature
    return float(1 / np.exp(flat - flat.max()).sum())


def probability(values: np.ndarray, cell: tuple[int, int], temperature: float) -> float:
    """Return a cell's calibrated probability, as judged() gives the best cell's."""
    flat = values.astype(np.float64) / temperature
    return float(np.exp(flat[cell] - flat.max()) / np.exp(flat - flat.max()).sum())


def mass_around(
    values: np.ndarray, grid: np.ndarray, cell: tuple[int, int], temperature: float
) -> float:
    """Return the calibrated mass on the landmark at `cell` and the cells touching it."""
    groups = footprints(grid, int(grid[cell]))
    [footprint] = [f for f in groups if tuple(cell) in map(tuple, f)]
    near = np.zeros(grid.shape, dtype=bool)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            rows, cols = footprint[:, 0] + dr, footprint[:, 1] + dc
            h, w = grid.shape
            inside = (rows >= 0) & (rows < h) & (cols >= 0) & (cols < w)
            near[rows[inside], cols[inside]] = True
    flat = values.astype(np.float64) / temperature
    p = np.exp(flat - flat.max())
    return float(p[near].sum() / p.sum())
