# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Grid world model: the MDP, value iteration, the policy of a value map, and the metrics.

Conventions (shared by every data set and the ROS layer):
- a grid is an (H, W) integer array of entity indices; row 0 is the top (north) row;
- the agent has 4 moves (up, down, left, right); a move off the map leaves it in place;
- reward is GOAL_REWARD (+3, terminal) at the goal, PUDDLE_REWARD (-1) on obstacle cells
  (puddles, or the other blocks in ISI), 0 elsewhere, the two adding up on a goal in a
  puddle; discount GAMMA = 0.9.

The metrics follow Janner et al.'s evaluation code (jannerm/spatial-reasoning,
pipeline/run_eval.py and score_iteration.py), which the paper's Table 1 compares against:
MSE over all cells, MD between argmax cells, PQ from score iteration of the softmax policy;
and HIT, the exact-goal rate, which MD averages away.
Everything here is batched numpy over maps: no Python loop over cells.
"""

from __future__ import annotations

import numpy as np

GAMMA = 0.9
GOAL_REWARD = 3.0
PUDDLE_REWARD = -1.0
# (d_row, d_col) of the 4 moves, in Janner's order: up, down, left, right.
ACTIONS = np.array([(-1, 0), (1, 0), (0, -1), (0, 1)])
ACTION_NAMES = ('up', 'down', 'left', 'right')


def next_cell_indices(height: int, width: int) -> np.ndarray:
    """(H*W, 4) flat index of the cell each move leads to; off-map moves stay put."""
    rows, cols = np.divmod(np.arange(height * width), width)
    nr = np.clip(rows[:, None] + ACTIONS[None, :, 0], 0, height - 1)
    nc = np.clip(cols[:, None] + ACTIONS[None, :, 1], 0, width - 1)
    return nr * width + nc


def step_cell(cell: tuple[int, int], action: int, shape: tuple[int, int]) -> tuple[int, int]:
    """Return the cell one move leads to (off-map moves stay put)."""
    if not 0 <= int(action) < len(ACTIONS):
        raise ValueError(f'action {action} is out of range 0..{len(ACTIONS) - 1}')
    r = min(max(cell[0] + int(ACTIONS[action][0]), 0), shape[0] - 1)
    c = min(max(cell[1] + int(ACTIONS[action][1]), 0), shape[1] - 1)
    return r, c


def reward_map(obstacles: np.ndarray, goal: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """
    Reward and terminal maps for one goal: -1 on obstacle cells, +3 (terminal) at the goal.

    The goal reward adds to the cell's own (a goal inside a puddle carries 2), as in the
    PuddleWorld pickles.
    """
    rewards = np.where(obstacles, PUDDLE_REWARD, 0.0).astype(np.float64)
    terminal = np.zeros(obstacles.shape, dtype=bool)
    rewards[goal] += GOAL_REWARD
    terminal[goal] = True
    return rewards, terminal


def value_iteration(
    rewards: np.ndarray,
    terminal: np.ndarray,
    gamma: float = GAMMA,
    tol: float = 1e-6,
    max_iter: int = 10_000,
) -> np.ndarray:
    """
    Optimal state values V(s) = R(s) + gamma * max_a V(next(s, a)); V = R at terminal cells.

    rewards, terminal: (H, W) or (B, H, W). Returns values of the same shape.
    """
    r, t = np.asarray(rewards, np.float64), np.asarray(terminal, bool)
    squeeze = r.ndim == 2
    if squeeze:
        r, t = r[None], t[None]
    b, h, w = r.shape
    nxt = next_cell_indices(h, w)
    r, t = r.reshape(b, -1), t.reshape(b, -1)
    v = r.copy()
    for _ in range(max_iter):
        new = np.where(t, r, r + gamma * v[:, nxt].max(axis=2))
        done = np.abs(new - v).max() < tol
        v = new
        if done:
            break
    v = v.reshape(b, h, w)
    return v[0] if squeeze else v


def greedy_policy(values: np.ndarray) -> np.ndarray:
    """
    Greedy action index per cell of a value map (H, W) -> (H, W).

    The move to the best next cell.
    """
    h, w = values.shape
    return values.reshape(-1)[next_cell_indices(h, w)].argmax(axis=1).reshape(h, w)


def softmax_policy(values: np.ndarray) -> np.ndarray:
    """pi_U(a|s) = softmax over the 4 moves of U(next cell): (B, H, W) -> (B, H*W, 4)."""
    b, h, w = values.shape
    nv = values.reshape(b, -1)[:, next_cell_indices(h, w)]
    nv = nv - nv.max(axis=2, keepdims=True)
    e = np.exp(nv)
    return e / e.sum(axis=2, keepdims=True)


def policy_scores(
    values: np.ndarray,
    rewards: np.ndarray,
    terminal: np.ndarray,
    gamma: float = GAMMA,
    tol: float = 0.01,
    max_iter: int = 10_000,
) -> np.ndarray:
    """
    Janner's score iteration: S(s) = R(s) at terminal cells, else R(s) + gamma * E_pi[S(next)].

    Iterates until the summed absolute change of each map is below `tol` (0.01 as in the
    reference code). Batched: (B, H, W) inputs, (B,) mean score per map.
    """
    b, h, w = values.shape
    nxt = next_cell_indices(h, w)
    pi = softmax_policy(values)
    r, t = rewards.reshape(b, -1).astype(np.float64), terminal.reshape(b, -1).astype(bool)
    s = np.zeros_like(r)
    active = np.ones(b, dtype=bool)
    for _ in range(max_iter):
        new = np.where(t, r, r + gamma * (pi * s[:, nxt]).sum(axis=2))
        change = np.abs(new - s).sum(axis=1)
        s = np.where(active[:, None], new, s)
        active &= change >= tol
        if not active.any():
            break
    return s.mean(axis=1)


def mse(pred: np.ndarray, true: np.ndarray) -> float:
    """Mean over all cells of all maps of the squared error."""
    return float(np.mean((np.asarray(pred, np.float64) - np.asarray(true, np.float64)) ** 2))


def argmax_cells(maps: np.ndarray) -> np.ndarray:
    """(B, H, W) -> (B, 2) row, column of each map's maximum (first one on ties)."""
    b, h, w = maps.shape
    return np.stack(np.divmod(maps.reshape(b, -1).argmax(axis=1), w), axis=1)


def manhattan_distances(pred: np.ndarray, true: np.ndarray) -> np.ndarray:
    """(B,) Manhattan distance between the argmax cells of predicted and true maps."""
    return np.abs(argmax_cells(pred) - argmax_cells(true)).sum(axis=1)


def policy_quality(
    pred: np.ndarray, true: np.ndarray, rewards: np.ndarray, terminal: np.ndarray
) -> np.ndarray:
    """(B,) PQ = (score(pred) - score(uniform)) / (score(true) - score(uniform))."""
    uniform = np.ones_like(true)
    sp = policy_scores(pred, rewards, terminal)
    st = policy_scores(true, rewards, terminal)
    su = policy_scores(uniform, rewards, terminal)
    return (sp - su) / (st - su)


def evaluate_maps(
    pred: np.ndarray, true: np.ndarray, rewards: np.ndarray, terminal: np.ndarray
) -> dict:
    """
    Return the paper's value-map metrics over a set of maps (all (B, H, W)), and HIT.

    The share of maps whose predicted argmax is the goal cell (the true map's unique maximum).
    """
    pred, true = np.asarray(pred, np.float64), np.asarray(true, np.float64)
    distances = manhattan_distances(pred, true)
    return {
        'mse': mse(pred, true),
        'pq': float(np.mean(policy_quality(pred, true, rewards, terminal))),
        'md': float(np.mean(distances)),
        'hit': float(np.mean(distances == 0)),
        'n': int(len(pred)),
    }
