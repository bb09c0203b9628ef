# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The RL environment.

A Gymnasium environment (gymnasium's own env checker passes); rewards and termination come from
the example's maps, moves from world.step_cell, and the true values never reach the observation.
"""

from gymnasium.utils.env_checker import check_env
import numpy as np
import pytest
from spatial_grounding_ros.core import world
from spatial_grounding_ros.data.generator import generate
from spatial_grounding_ros.training.env import GridWorldEnv, load_episodes


@pytest.fixture(scope='module')
def data():
    return generate(20, seed=3, mode='mixed')


def test_reset_observation_has_no_values(data):
    env = GridWorldEnv(data)
    obs, info = env.reset(seed=0)
    assert set(obs) == {'grid', 'instruction', 'agent'}
    assert obs['grid'].shape == (10, 10) and isinstance(obs['instruction'], str)
    assert not data.terminal[info['example']][obs['agent']]  # never starts on the goal


def test_gymnasium_env_checker_passes(data):
    """Gymnasium's own checker: spaces, reset(seed=) determinism, the step 5-tuple."""
    env = GridWorldEnv(data)
    check_env(env, skip_render_check=True)
    assert env.action_space.n == 4
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs)


def test_reset_seed_sets_the_rng_and_observations_are_copies(data):
    env = GridWorldEnv(data)
    first = [env.reset(seed=7)] + [env.reset() for _ in range(5)]
    again = [env.reset(seed=7)] + [env.reset() for _ in range(5)]
    assert [(i['example'], o['agent']) for o, i in first] == [
        (i['example'], o['agent']) for o, i in again
    ]
    obs, info = env.reset(seed=0)
    obs['grid'][:] = -1  # changing an observation leaves the data set alone
    assert (data.grids[info['example']] >= 0).all()
    with pytest.raises(ValueError, match='unknown reset option'):
        env.reset(options={'exemple': 0})


def test_walk_to_goal_collects_rewards_and_terminates(data):
    env = GridWorldEnv(data, step_limit=100)
    env.reset(seed=1, options={'example': 4, 'start': (0, 0)})
    goal = env.goal
    expected = 0.0
    policy = world.greedy_policy(data.values[4])  # the optimal policy reaches the goal
    for _ in range(100):
        a = int(policy[env.agent])
        nxt = world.step_cell(env.agent, a, env.shape)
        obs, reward, terminated, truncated, info = env.step(a)
        assert obs['agent'] == nxt
        assert reward == data.rewards[4][nxt]
        expected += reward
        if terminated:
            break
    assert terminated and not truncated and env.agent == goal
    assert info['total_reward'] == pytest.approx(expected)
    assert data.rewards[4][goal] >= 2.0
    with pytest.raises(RuntimeError):
        env.step(0)


def test_off_map_stays_put_and_step_limit_truncates(data):
    env = GridWorldEnv(data, step_limit=3)
    env.reset(options={'example': 0, 'start': (0, 0)})
    if env.goal == (0, 0):
        pytest.skip('goal in the corner')
    for i in range(3):
        obs, reward, terminated, truncated, _ = env.step(0)  # up, off the map
        assert obs['agent'] == (0, 0)
        assert reward == data.rewards[0][0, 0]
    assert truncated and not terminated


def test_puddle_reward_is_minus_one(data):
    env = GridWorldEnv(data)
    i = next(i for i in range(len(data)) if (data.grids[i] == 1).any())
    cell = tuple(np.argwhere(data.grids[i] == 1)[0])
    if data.terminal[i][cell]:
        pytest.skip('puddle is the goal')
    # enter the puddle cell from a neighbour
    for a, (dr, dc) in enumerate(world.ACTIONS):
        start = (cell[0] - dr, cell[1] - dc)
        if 0 <= start[0] < 10 and 0 <= start[1] < 10 and not data.terminal[i][start]:
            env.reset(options={'example': i, 'start': start})
            _, reward, _, _, _ = env.step(a)
            assert reward == -1.0
            return
    pytest.skip('no free neighbour')


def test_bad_input(data):
    env = GridWorldEnv(data)
    with pytest.raises(RuntimeError):
        env.step(0)
    env.reset(options={'example': 0})
    with pytest.raises(ValueError):
        env.step(4)
    with pytest.raises(ValueError):
        env.reset(options={'example': len(data)})
    with pytest.raises(ValueError):
        env.reset(options={'example': 0, 'start': (10, 0)})
    with pytest.raises(ValueError):
        GridWorldEnv(data, step_limit=0)


def test_sequential_order_and_generator_source():
    data = load_episodes('generator-local', n=3, seed=1)
    env = GridWorldEnv(data, order='sequential')
    seen = [env.reset()[1]['example'] for _ in range(4)]
    assert seen == [0, 1, 2, 0]


def test_puddleworld_episodes(data_dir):
    """
    Check the episodes of a data set split.

    Episodes of a data set split (read from SPATIAL_GROUNDING_DATA or ../shared/data, the
    data_dir fixture): the example's own map, instruction and rewards.
    """
    data = load_episodes('pw-local', 'test', str(data_dir))
    assert len(data) == 399
    env = GridWorldEnv(data)
    obs, info = env.reset(seed=0)
    i = info['example']
    assert obs['instruction'] == data.instructions[i] and np.array_equal(
        obs['grid'], data.grids[i]
    )
    _, reward, _, _, _ = env.step(3)
    assert reward == data.rewards[i][env.agent]
    check_env(env, skip_render_check=True)  # human instructions: the space holds their text
