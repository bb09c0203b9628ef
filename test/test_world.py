"""World model and metrics: value iteration against the data set, PQ and MD by hand."""
import glob
import pickle

import numpy as np
import pytest

from spatial_grounding_ros import world


def test_value_iteration_reproduces_every_puddleworld_pickle(data_dir):
    files = sorted(glob.glob(str(data_dir / "puddleworld" / "*" / "*.p")))
    assert len(files) == 400
    checked = 0
    for path in files:
        with open(path, "rb") as f:
            info = pickle.load(f, encoding="latin1")
        if not info["goals"]:
            continue
        values = world.value_iteration(np.array(info["rewards"]), np.array(info["terminal"]))
        assert np.abs(values - np.array(info["values"])).max() < 1e-3, path
        checked += len(values)
    assert checked > 16000


def test_reward_map_matches_pickles_including_goal_in_puddle(data_dir):
    with open(data_dir / "puddleworld" / "global" / "37.p", "rb") as f:
        info = pickle.load(f, encoding="latin1")
    for goal, rewards in zip(info["goals"], info["rewards"]):
        mine, terminal = world.reward_map(info["map"] == 1, tuple(int(x) for x in goal))
        np.testing.assert_array_equal(mine, rewards)
        assert terminal.sum() == 1


def _square_world(goal=(2, 3), size=5):
    puddles = np.zeros((size, size), bool)
    puddles[0, :] = True
    rewards, terminal = world.reward_map(puddles, goal)
    return rewards, terminal, world.value_iteration(rewards, terminal)


def test_value_iteration_by_hand():
    rewards, terminal, v = _square_world()
    assert v[2, 3] == pytest.approx(3.0)
    assert v[2, 2] == pytest.approx(0.9 * 3)
    assert v[4, 0] == pytest.approx(3 * 0.9 ** 5)
    assert v[0, 3] == pytest.approx(-1 + 0.9 * 0.9 * 3)   # a puddle two cells from the goal


def test_off_map_moves_stay_put():
    assert world.step_cell((0, 0), 0, (3, 3)) == (0, 0)
    assert world.step_cell((0, 0), 1, (3, 3)) == (1, 0)
    assert world.step_cell((2, 2), 3, (3, 3)) == (2, 2)
    with pytest.raises(ValueError, match="out of range"):
        world.step_cell((0, 0), 4, (3, 3))


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
    true[0, 1, 1] = pred[0, 1, 1] = 1      # same cell
    true[1, 0, 0], pred[1, 3, 2] = 1, 1     # 3 + 2 away
    np.testing.assert_array_equal(world.manhattan_distances(pred, true), [0, 5])
    assert world.evaluate_maps(pred, true, np.zeros_like(true), true > 0)["md"] == 2.5


def test_mse_is_mean_over_all_cells_of_all_maps():
    assert world.mse(np.zeros((2, 3, 3)), np.full((2, 3, 3), 2.0)) == 4.0


def test_greedy_policy_moves_towards_goal():
    _, _, v = _square_world()
    policy = world.greedy_policy(v)
    assert world.ACTION_NAMES[policy[2, 0]] == "right"
    assert world.ACTION_NAMES[policy[4, 3]] == "up"
