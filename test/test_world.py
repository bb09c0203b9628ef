# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""World model and metrics: value iteration against the data set; PQ, MD and HIT by hand."""

import glob
import pickle

import numpy as np
import pytest
import reference
from spatial_grounding_ros.core import world


def test_value_iteration_reproduces_every_puddleworld_pickle(data_dir):
    files = sorted(glob.glob(str(data_dir / 'puddleworld' / '*' / '*.p')))
    assert len(files) == 400
    checked = 0
    for path in files:
        with open(path, 'rb') as f:
            info = pickle.load(f, encoding='latin1')
        if not info['goals']:
            continue
        values = world.value_iteration(np.array(info['rewards']), np.array(info['terminal']))
        assert np.abs(values - np.array(info['values'])).max() < 1e-3, path
        checked += len(values)
    assert checked > 16000


def test_reward_map_matches_pickles_including_goal_in_puddle(data_dir):
    with open(data_dir / 'puddleworld' / 'global' / '37.p', 'rb') as f:
        info = pickle.load(f, encoding='latin1')
    in_puddle = 0
    for goal, rewards in zip(info['goals'], info['rewards']):
        goal = tuple(int(x) for x in goal)
        mine, terminal = world.reward_map(info['map'] == 1, goal)
        np.testing.assert_array_equal(mine, rewards)
        assert terminal.sum() == 1 and terminal[goal]
        if info['map'][goal] == 1:  # the case this world is here for: 3 - 1 = 2
            assert mine[goal] == rewards[goal] == 2.0
            in_puddle += 1
    assert in_puddle > 0, 'world 37 was picked for its goal in a puddle'


def _square_world(goal=(2, 3), size=5):
    puddles = np.zeros((size, size), bool)
    puddles[0, :] = True
    rewards, terminal = world.reward_map(puddles, goal)
    return rewards, terminal, world.value_iteration(rewards, terminal)


def test_value_iteration_by_hand():
    rewards, terminal, v = _square_world()
    assert v[2, 3] == pytest.approx(3.0)
    assert v[2, 2] == pytest.approx(0.9 * 3)
    assert v[4, 0] == pytest.approx(3 * 0.9**5)
    assert v[0, 3] == pytest.approx(-1 + 0.9 * 0.9 * 3)  # a puddle two cells from the goal


def test_off_map_moves_stay_put():
    assert world.step_cell((0, 0), 0, (3, 3)) == (0, 0)
    assert world.step_cell((0, 0), 1, (3, 3)) == (1, 0)
    assert world.step_cell((2, 2), 3, (3, 3)) == (2, 2)
    with pytest.raises(ValueError, match='out of range'):
        world.step_cell((0, 0), 4, (3, 3))


# Score iteration by hand on 1-row maps. From a cell, 3 of the 4 moves (up, down, and off
# the near end) stay put; S starts at 0 and the sweep whose summed change is below 0.01 is
# the last one kept.


def _row(rewards, goal):
    rewards = np.array([rewards], float)
    terminal = np.zeros(rewards.shape, bool)
    terminal[0, goal] = True
    return rewards[None], terminal[None]


def test_score_iteration_by_hand_on_a_1x2_map():
    """
    Goal (+3) on the right of a 1x2 map, uniform policy (all-ones map: 1/4 per move).

    Converged: S0 = 0.9 * (3/4 S0 + 1/4 * 3), so S0 = 0.675 / 0.325 and the mean score is
    (0.675 / 0.325 + 3) / 2 = 2.538. With the stopping rule: sweep 1 gives S = (0, 3)
    (change 3), then S0 = 0.675 + 0.675 S0 each sweep, a change of 0.675^(k-1) at sweep k;
    0.675^11 = 0.0133 and 0.675^12 = 0.0089 < 0.01, so sweep 13 is the last:
    S0 = 0.675 (1 - 0.675^12) / 0.325 = 2.0583 and the mean is 2.529.
    """
    rewards, terminal = _row([0, 3], 1)
    uniform = np.ones((1, 1, 2))
    converged = world.policy_scores(uniform, rewards, terminal, tol=1e-12)[0]
    assert converged == pytest.approx((0.675 / 0.325 + 3) / 2, abs=1e-9)
    assert round(converged, 3) == 2.538
    stopped = world.policy_scores(uniform, rewards, terminal)[0]
    assert stopped == pytest.approx((0.675 * (1 - 0.675**12) / 0.325 + 3) / 2, abs=1e-12)
    assert round(stopped, 3) == 2.529


def test_score_iteration_by_hand_with_a_puddle_and_on_a_1x3_map():
    """
    Puddle (-1) left of the goal on a 1x2 map, uniform policy.

    S0 = -1 + 0.9 * (3/4 S0 + 1/4 * 3) = -0.325 + 0.675 S0, so S0 = -1, which sweep 2 already
    reaches exactly (sweep 1: S0 = -1 + 0.9 * 0 = -1): mean (-1 + 3) / 2 = 1. A 1x3 map, goal on
    the right, uniform policy, converged: S0 = 0.9 (3/4 S0 + 1/4 S1) and S1 = 0.9 (1/2 S1 + 1/4 S0
    + 1/4 * 3), so S0 = 9/13 S1 and S1 (0.55 - 0.225 * 9/13) = 0.675: S1 = 0.675 * 13 / 5.125 =
    1.71220, S0 = 1.18537, mean (S0 + S1 + 3) / 3 = 1.96585.
    """
    rewards, terminal = _row([-1, 3], 1)
    assert world.policy_scores(np.ones((1, 1, 2)), rewards, terminal)[0] == 1.0
    rewards, terminal = _row([0, 0, 3], 2)
    s1 = 0.675 * 13 / 5.125
    mean = (9 / 13 * s1 + s1 + 3) / 3
    assert round(mean, 5) == 1.96585
    assert world.policy_scores(np.ones((1, 1, 3)), rewards, terminal, tol=1e-12)[
        0
    ] == pytest.approx(mean, abs=1e-9)


def test_pq_by_hand_on_a_1x2_map():
    """
    Check PQ = (score(pred) - score(uniform)) / (score(true) - score(uniform)).

    PQ = (score(pred) - score(uniform)) / (score(true) - score(uniform)), all with the
    stopping rule. True map (2.7, 3): from cell 0, p = P(right) = e^3 / (3 e^2.7 + e^3)
    = 1 / (1 + 3 e^-0.3) = 0.31032; with q = 0.9 (1 - p), sweep k >= 2 changes S0 by
    2.7 p q^(k-2), below 0.01 first at k = 12, so S0 = 2.7 p (1 - q^11) / (1 - q) = 2.1974
    and the mean is 2.5987. A peaked map (0, 100) moves right for sure: S0 = 2.7, mean 2.85.
    Uniform (above): 2.52917. PQ = (2.85 - 2.52917) / (2.59870 - 2.52917) = 4.614: a map
    sharper than the truth scores above 1, which "1 for the truth" alone would not show.
    """
    rewards, terminal = _row([0, 3], 1)
    true = world.value_iteration(rewards, terminal)
    np.testing.assert_allclose(true, [[[2.7, 3.0]]])
    p = 1 / (1 + 3 * np.exp(-0.3))
    q = 0.9 * (1 - p)
    assert 2.7 * p * q**9 >= 0.01 > 2.7 * p * q**10
    s_true = (2.7 * p * (1 - q**11) / (1 - q) + 3) / 2
    s_uniform = (0.675 * (1 - 0.675**12) / 0.325 + 3) / 2
    expected = (2.85 - s_uniform) / (s_true - s_uniform)
    assert round(expected, 3) == 4.614
    peaked = np.array([[[0.0, 100.0]]])
    assert world.policy_scores(true, rewards, terminal)[0] == pytest.approx(s_true, abs=1e-12)
    assert world.policy_quality(peaked, true, rewards, terminal)[0] == pytest.approx(
        expected, abs=1e-9
    )


def test_score_iteration_equals_a_cell_by_cell_reference():
    """
    Check world.policy_scores against test/reference.py's loops over cells.

    world.policy_scores (batched numpy) against test/reference.py's loops over cells, on
    random 5x5 and 4x7 maps with puddles, a goal in a puddle among them, stopping rule included.
    """
    rng = np.random.default_rng(0)
    for shape in [(5, 5), (4, 7)]:
        for n in range(4):
            puddles = rng.random(shape) < 0.3
            goal = tuple(int(x) for x in rng.integers(shape))
            if n == 0:
                puddles[goal] = True
            rewards, terminal = world.reward_map(puddles, goal)
            pred = rng.normal(size=shape) * 2
            got = world.policy_scores(pred[None], rewards[None], terminal[None])[0]
            assert got == pytest.approx(
                reference.mean_policy_score(pred, rewards, terminal), abs=1e-12
            )


def test_value_iteration_equals_the_reference():
    rng = np.random.default_rng(1)
    puddles = rng.random((6, 5, 8)) < 0.3
    goals = [tuple(int(x) for x in rng.integers((5, 8))) for _ in range(6)]
    rewards, terminal = map(
        np.stack, zip(*(world.reward_map(p, g) for p, g in zip(puddles, goals)))
    )
    np.testing.assert_allclose(
        world.value_iteration(rewards, terminal),
        reference.value_iteration(rewards, terminal),
        atol=1e-5,
    )


def test_pq_is_one_for_truth_zero_for_uniform_and_negative_for_inverse():
    rewards, terminal, v = _square_world()
    maps = np.stack([v, np.ones_like(v), -v])
    r, t = np.stack([rewards] * 3), np.stack([terminal] * 3)
    pq = world.policy_quality(maps, np.stack([v] * 3), r, t)
    assert pq[0] == pytest.approx(1.0)
    assert pq[1] == pytest.approx(0.0)
    assert pq[2] < 0


def test_a_sharper_map_scores_above_the_truth():
    # a sharper map (same argmax everywhere) gives a better softmax policy than the truth
    rewards, terminal, v = _square_world()
    pq = world.policy_quality((3 * v)[None], v[None], rewards[None], terminal[None])
    assert pq[0] > 1.0


def test_md_by_hand():
    true = np.zeros((2, 4, 4))
    pred = np.zeros((2, 4, 4))
    true[0, 1, 1] = pred[0, 1, 1] = 1  # same cell
    true[1, 0, 0], pred[1, 3, 2] = 1, 1  # 3 + 2 away
    np.testing.assert_array_equal(world.manhattan_distances(pred, true), [0, 5])
    assert world.evaluate_maps(pred, true, np.zeros_like(true), true > 0)['md'] == 2.5


# Five hand-built 3x3 value maps and their goals; cells are (row, col), row-major order,
# and a tie goes to the first cell in that order (numpy's argmax, as the node's Grounder).
HAND_PRED = np.array(
    [
        # a hit on an all-negative map: the largest value, -0.5, not the largest magnitude
        [[-3.0, -2.0, -3.0], [-2.0, -0.5, -2.0], [-3.0, -2.0, -3.0]],
        # a miss across the map: argmax (0, 2), goal (2, 0): MD 2 + 2 = 4
        [[0.0, 1.0, 9.0], [0.0, 1.0, 2.0], [3.0, 0.0, 0.0]],
        # a tie that holds the goal second: 7 at (0, 1) and (2, 2); the first, (0, 1), is
        # taken, goal (2, 2): a miss, MD 2 + 1 = 3
        [[0.0, 7.0, 0.0], [1.0, 2.0, 3.0], [0.0, 6.0, 7.0]],
        # a tie that holds the goal first: 4 at (1, 0) and (1, 2), goal (1, 0): a hit, MD 0
        [[0.0, 1.0, 0.0], [4.0, 0.0, 4.0], [0.0, 1.0, 0.0]],
        # a near miss: argmax (2, 1), goal (2, 2): MD 1
        [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 5.0, 4.9]],
    ]
)
HAND_GOALS = np.array([(1, 1), (2, 0), (2, 2), (1, 0), (2, 2)])
# HIT = 2 hits / 5 = 0.4; MD = (0 + 4 + 3 + 0 + 1) / 5 = 8 / 5 = 1.6
HAND_HIT, HAND_MD = 0.4, 1.6


def hand_truth():
    """Return the true maps, rewards and terminals: value iteration, +3 at each goal."""
    rewards, terminal = map(
        np.stack, zip(*(world.reward_map(np.zeros((3, 3), bool), tuple(g)) for g in HAND_GOALS))
    )
    return world.value_iteration(rewards, terminal), rewards, terminal


def test_hit_and_md_by_hand_with_ties_and_misses():
    true, rewards, terminal = hand_truth()
    np.testing.assert_array_equal(world.argmax_cells(true), HAND_GOALS)
    np.testing.assert_array_equal(
        world.argmax_cells(HAND_PRED), [(1, 1), (0, 2), (0, 1), (1, 0), (2, 1)]
    )
    np.testing.assert_array_equal(world.manhattan_distances(HAND_PRED, true), [0, 4, 3, 0, 1])
    metrics = world.evaluate_maps(HAND_PRED, true, rewards, terminal)
    assert metrics['hit'] == HAND_HIT and metrics['md'] == pytest.approx(HAND_MD)
    assert metrics['n'] == 5


def test_every_hit_and_md_agree_on_the_hand_maps():
    """
    The per-epoch HIT of training and the bag's HIT and MD are the same numbers.

    supervised.evaluate_hit (a model that answers the hand maps) and eval-bag's
    BagEvaluation.metrics (goal_pose cells that are the maps' argmax cells) give 0.4 and 1.6.
    """
    import torch
    from spatial_grounding_ros.core.entities import PUDDLEWORLD
    from spatial_grounding_ros.core.text import Vocabulary
    from spatial_grounding_ros.data.bags import BagEvaluation, Episode
    from spatial_grounding_ros.data.datasets import GroundingSet
    from spatial_grounding_ros.training.supervised import evaluate_hit

    true, rewards, terminal = hand_truth()
    texts = ['reach cell with star'] * len(HAND_PRED)
    data = GroundingSet(
        'hand', PUDDLEWORLD, np.zeros((5, 3, 3), np.int64), texts, true.astype(np.float32),
        rewards.astype(np.float32), terminal, HAND_GOALS,
    )

    class HandModel(torch.nn.Module):
        def forward(self, grids, tokens):
            return torch.from_numpy(HAND_PRED[: len(grids)]).float()

    assert evaluate_hit(HandModel(), Vocabulary.build(texts), data) == HAND_HIT
    bag = BagEvaluation(
        episodes=[
            Episode(t, tuple(int(x) for x in a), tuple(int(x) for x in g), p, v, r)
            for t, a, g, p, v, r in zip(
                texts, world.argmax_cells(HAND_PRED), HAND_GOALS, HAND_PRED, true, rewards
            )
        ]
    )
    metrics = bag.metrics()
    assert metrics['hit'] == HAND_HIT and metrics['md'] == pytest.approx(HAND_MD)
    assert metrics['pq'] == pytest.approx(
        world.evaluate_maps(HAND_PRED, true, rewards, terminal)['pq']
    )


def test_pq_by_hand_on_a_two_cell_world():
    """
    PQ, MD, HIT and MSE worked by hand on a 1x2 world.

    The goal A (terminal, reward 3) and B (reward 0) east of it. From B the four moves lead
    to: up B, down B (off the map: stay), left A, right B (off). Score iteration from S = 0:
    S = R at the terminal, else R + 0.9 * E_pi[S(next)], sweeps until the summed change of a
    sweep is under 0.01; a score is the mean over the cells.
    - `toward` (50 on A, 0 on B): pi(left | B) = 1 - 3e-22, 1.0 in float64: sweep 1 gives
      S = (3, 0), sweep 2 S(B) = 0.9 * 3 = 2.7, sweep 3 no change: score (3 + 2.7) / 2 = 2.85.
    - `away` (0 on A, 50 on B): pi(left | B) = 6e-22: S(B) stays 0 (to 1e-21): score 1.5.
    - uniform (equal values): pi = 1/4 each, S(B) = 0.9 * (S(A) + 3 S(B)) / 4. Sweep k >= 2
      gives S(B) = (27/13) (1 - 0.675^(k-1)), a change of 0.675^(k-1): 0.675^11 = 0.0133 is
      not under 0.01, 0.675^12 = 0.0089 is, so it stops after sweep 13 with S(B) =
      (27/13) (1 - 0.675^12) = 2.0583: score su = 2.5292.
    PQ = (score(pred) - su) / (score(true) - su): with `toward` as the truth, `away` scores
    (1.5 - su) / (2.85 - su) = -3.208, `toward` itself 1. MD: argmax (0, 1) against (0, 0):
    1, no hit. MSE: (50^2 + 50^2) / 2 = 2500.
    """
    toward, away = np.array([[[50.0, 0.0]]]), np.array([[[0.0, 50.0]]])
    rewards, terminal = np.array([[[3.0, 0.0]]]), np.array([[[True, False]]])
    assert world.policy_scores(toward, rewards, terminal)[0] == pytest.approx(2.85, abs=1e-15)
    assert world.policy_scores(away, rewards, terminal)[0] == pytest.approx(1.5, abs=1e-15)
    su = (3 + 27 / 13 * (1 - 0.675**12)) / 2
    uniform = np.ones_like(toward)
    assert world.policy_scores(uniform, rewards, terminal)[0] == pytest.approx(su, rel=1e-12)
    assert su == pytest.approx(2.5292, abs=1e-4)
    metrics = world.evaluate_maps(away, toward, rewards, terminal)
    assert metrics['pq'] == pytest.approx((1.5 - su) / (2.85 - su), rel=1e-9)
    assert metrics['pq'] == pytest.approx(-3.208, abs=1e-3)
    assert (metrics['md'], metrics['hit'], metrics['mse']) == (1.0, 0.0, 2500.0)
    assert world.evaluate_maps(toward, toward, rewards, terminal)['pq'] == pytest.approx(1.0)


def test_mse_is_mean_over_all_cells_of_all_maps():
    assert world.mse(np.zeros((2, 3, 3)), np.full((2, 3, 3), 2.0)) == 4.0


def test_greedy_policy_moves_towards_goal():
    _, _, v = _square_world()
    policy = world.greedy_policy(v)
    assert world.ACTION_NAMES[policy[2, 0]] == 'right'
    assert world.ACTION_NAMES[policy[4, 3]] == 'up'
