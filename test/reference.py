# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Reference implementations of the metrics' building blocks, written apart from world.py to check it.

Plain loops over cells and moves (score iteration) or edge-padded shifts (value iteration), from
the definitions in DESIGN.md, sharing no code with the package.

Conventions (DESIGN.md): 4 moves up, down, left, right; a move off the map stays put;
gamma 0.9; a terminal cell's value (or score) is its reward.
"""

from __future__ import annotations

import math

import numpy as np

GAMMA = 0.9
MOVES = ((-1, 0), (1, 0), (0, -1), (0, 1))


def next_cell(r: int, c: int, move: tuple[int, int], h: int, w: int) -> tuple[int, int]:
    nr, nc = r + move[0], c + move[1]
    return (nr, nc) if 0 <= nr < h and 0 <= nc < w else (r, c)


def mean_policy_score(values, rewards, terminal, gamma: float = GAMMA, tol: float = 0.01) -> float:
    """
    Janner's score iteration for one (H, W) map, cell by cell.

    pi(a|s) = softmax over the 4 moves of values[next(s, a)]; S starts at 0, and each sweep (from
    the previous sweep's S) sets S(s) = R(s) at terminal cells, R(s) + gamma * sum_a pi(a|s)
    S(next(s, a)) elsewhere; the sweep whose summed absolute change is below `tol` is the last one
    kept. Returns the mean of S over the cells.
    """
    values, rewards, terminal = (np.asarray(x).tolist() for x in (values, rewards, terminal))
    h, w = len(values), len(values[0])
    policy = {}
    for r in range(h):
        for c in range(w):
            nexts = [next_cell(r, c, m, h, w) for m in MOVES]
            top = max(values[nr][nc] for nr, nc in nexts)
            e = [math.exp(values[nr][nc] - top) for nr, nc in nexts]
            policy[r, c] = [(x / sum(e), cell) for x, cell in zip(e, nexts)]
    s = [[0.0] * w for _ in range(h)]
    for _ in range(100_000):
        new = [
            [
                rewards[r][c]
                if terminal[r][c]
                else rewards[r][c] + gamma * sum(p * s[nr][nc] for p, (nr, nc) in policy[r, c])
                for c in range(w)
            ]
            for r in range(h)
        ]
        change = sum(abs(new[r][c] - s[r][c]) for r in range(h) for c in range(w))
        s = new
        if change < tol:
            break
    return sum(map(sum, s)) / (h * w)


def policy_quality(pred, true, rewards, terminal) -> float:
    """PQ of one map: (score(pred) - score(uniform)) / (score(true) - score(uniform))."""
    uniform = np.ones(np.shape(true))
    su = mean_policy_score(uniform, rewards, terminal)
    return (mean_policy_score(pred, rewards, terminal) - su) / (
        mean_policy_score(true, rewards, terminal) - su
    )


def value_iteration(rewards, terminal, gamma: float = GAMMA, tol: float = 1e-9) -> np.ndarray:
    """
    Optimal values of (B, H, W) reward and terminal maps.

    V = R at terminal cells, else R + gamma * the best neighbour's V, a move off the map staying
    put (edge padding).
    """
    r, t = np.asarray(rewards, np.float64), np.asarray(terminal, bool)
    v = np.zeros_like(r)
    while True:
        p = np.pad(v, ((0, 0), (1, 1), (1, 1)), mode='edge')
        best = np.maximum.reduce(
            [p[:, :-2, 1:-1], p[:, 2:, 1:-1], p[:, 1:-1, :-2], p[:, 1:-1, 2:]]
        )
        new = np.where(t, r, r + gamma * best)
        if np.abs(new - v).max() < tol:
            return new
        v = new
