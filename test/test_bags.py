# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
eval-bag on a bag written by another tool, and on bad input.

eval-bag on a bag written by another tool (rosbags directly, standard message types
only) and bad input: missing, non-bag, truncated, bag without the needed topics.
"""

import json

import numpy as np
import pytest
import reference
from spatial_grounding_ros import cli
from spatial_grounding_ros.core import world
from spatial_grounding_ros.data.bags import BagWriter, evaluate_bag, typestore

STORE = typestore()
T = STORE.types


def header(frame='map'):
    return T['std_msgs/msg/Header'](
        stamp=T['builtin_interfaces/msg/Time'](sec=0, nanosec=0), frame_id=frame
    )


def pose_at(cell, height=10, resolution=0.5):
    """Return a PoseStamped at the centre of data-set cell (row, col) of a map at origin (0, 0)."""
    P = T['geometry_msgs/msg/Pose']
    point = T['geometry_msgs/msg/Point'](
        x=(cell[1] + 0.5) * resolution, y=(height - 1 - cell[0] + 0.5) * resolution, z=0.0
    )
    q = T['geometry_msgs/msg/Quaternion'](x=0.0, y=0.0, z=0.0, w=1.0)
    return T['geometry_msgs/msg/PoseStamped'](
        header=header(), pose=P(position=point, orientation=q)
    )


def occupancy(grid, resolution=0.5):
    h, w = grid.shape
    P = T['geometry_msgs/msg/Pose']
    origin = P(
        position=T['geometry_msgs/msg/Point'](x=0.0, y=0.0, z=0.0),
        orientation=T['geometry_msgs/msg/Quaternion'](x=0.0, y=0.0, z=0.0, w=1.0),
    )
    zero = T['builtin_interfaces/msg/Time'](sec=0, nanosec=0)
    info = T['nav_msgs/msg/MapMetaData'](
        map_load_time=zero, resolution=resolution, width=w, height=h, origin=origin
    )
    return T['nav_msgs/msg/OccupancyGrid'](
        header=header(), info=info, data=grid[::-1].astype(np.int8).reshape(-1)
    )


def multiarray(values):
    values = np.asarray(values, np.float32)[::-1]
    h, w = values.shape
    D = T['std_msgs/msg/MultiArrayDimension']
    layout = T['std_msgs/msg/MultiArrayLayout'](
        dim=[D(label='height', size=h, stride=h * w), D(label='width', size=w, stride=w)],
        data_offset=0,
    )
    return T['std_msgs/msg/Float32MultiArray'](layout=layout, data=values.reshape(-1))


def write_bag(
    path,
    episodes,
    with_values=False,
    skip=(),
    puddles=None,
    noise=0.0,
    names=None,
    other_goals=None,
):
    """
    Write a bag of episodes.

    episodes: (instruction, answered cell, true cell); gridworld order: truth, then instruction,
    then goal (and value map). The predicted map is the true map of the answered cell, plus `noise`
    times a seeded normal; `names` renames topics (role -> topic); `other_goals` (topic -> one cell
    per episode) adds a second answerer's goals. With values, returns the path and the float32 maps
    written: (predicted, true values, true rewards) per answered episode.
    """
    puddles = np.zeros((10, 10), bool) if puddles is None else puddles
    grid = puddles.astype(np.int64)  # entity 1 = puddle
    topic = {
        'map': '/entity_map',
        'truth': '/true_goal',
        'true_values': '/true_value_map',
        'true_rewards': '/true_reward_map',
        'instruction': '/instruction',
        'goal': '/goal_pose',
        'values': '/value_map_raw',
        **(names or {}),
    }
    rng = np.random.default_rng(0)
    written = []
    t = 1
    with BagWriter(path) as bag:
        if 'map' not in skip:
            bag.write_message(topic['map'], 'nav_msgs/msg/OccupancyGrid', t, occupancy(grid))
        for n, (text, answer, truth) in enumerate(episodes):
            rewards, terminal = world.reward_map(puddles, truth)
            values = world.value_iteration(rewards, terminal)
            t += 10
            bag.write_message(topic['truth'], 'geometry_msgs/msg/PoseStamped', t, pose_at(truth))
            if with_values:
                bag.write_message(
                    topic['true_values'],
                    'std_msgs/msg/Float32MultiArray',
                    t + 1,
                    multiarray(values),
                )
                bag.write_message(
                    topic['true_rewards'],
                    'std_msgs/msg/Float32MultiArray',
                    t + 1,
                    multiarray(rewards),
                )
            bag.write_message(
                topic['instruction'],
                'std_msgs/msg/String',
                t + 2,
                T['std_msgs/msg/String'](data=text),
            )
            if answer is not None:
                bag.write_message(
                    topic['goal'], 'geometry_msgs/msg/PoseStamped', t + 3, pose_at(answer)
                )
                for other, cells in (other_goals or {}).items():
                    bag.write_message(
                        other, 'geometry_msgs/msg/PoseStamped', t + 3, pose_at(cells[n])
                    )
                if with_values:
                    r2, t2 = world.reward_map(puddles, answer)
                    pred = world.value_iteration(r2, t2) + noise * rng.normal(size=(10, 10))
                    bag.write_message(
                        topic['values'], 'std_msgs/msg/Float32MultiArray', t + 4, multiarray(pred)
                    )
                    written.append(tuple(np.float32(m) for m in (pred, values, rewards)))
    return (path, written) if with_values else path


def test_md_from_a_standard_types_bag(tmp_path, capsys):
    bag = write_bag(
        tmp_path / 'bag',
        [('a', (1, 1), (1, 1)), ('b', (2, 3), (4, 4)), ('c', None, (0, 0)), ('d', (9, 0), (0, 0))],
    )
    m = evaluate_bag(bag).metrics()
    assert m['n'] == 3 and m['unanswered'] == 1
    assert m['md'] == pytest.approx((0 + 3 + 9) / 3)
    assert 'pq' not in m
    assert cli.main(['eval-bag', str(bag), '--json']) == 0
    out = json.loads(capsys.readouterr().out)
    assert out['n'] == 3 and out['md'] == pytest.approx(4.0)


def test_pq_and_mse_when_value_maps_are_recorded(tmp_path):
    """
    Check eval-bag's MSE and PQ against numpy's MSE and test/reference.py's PQ.

    MSE and PQ of eval-bag equal numpy's MSE and test/reference.py's cell-by-cell PQ of
    the very float32 maps written into the bag (a map with puddles, noisy predictions, one
    answer off by a cell). The truth's cell is the terminal one.
    """
    puddles = np.zeros((10, 10), bool)
    puddles[4:7, 2] = puddles[0, 5:8] = True
    episodes = [('a', (1, 1), (1, 1)), ('b', (5, 5), (5, 6)), ('c', (8, 8), (0, 6))]
    bag, written = write_bag(
        tmp_path / 'bag', episodes, with_values=True, puddles=puddles, noise=0.3
    )
    pred, true, rewards = (np.stack(m).astype(np.float64) for m in zip(*written))
    m = evaluate_bag(bag).metrics()
    assert m['n'] == 3 and m['n_value_maps'] == 3
    assert m['md'] == pytest.approx((0 + 1 + 10) / 3)
    assert m['mse'] == pytest.approx(np.mean((pred - true) ** 2), rel=1e-12)
    terminal = np.zeros(true.shape, bool)
    for t, (_, _, truth) in zip(terminal, episodes):
        t[truth] = True
    pq = [reference.policy_quality(*maps) for maps in zip(pred, true, rewards, terminal)]
    # eval-bag takes the softmax of the float32 maps in float32: agreement to about 1e-8
    assert m['pq'] == pytest.approx(np.mean(pq), abs=1e-6)
    assert pq[0] > pq[2]  # the right answer (noisy) above the one 10 cells off
    perfect, _ = write_bag(tmp_path / 'bag2', [('a', (2, 2), (2, 2))], with_values=True)
    perfect = evaluate_bag(perfect).metrics()
    assert perfect['pq'] == pytest.approx(1.0) and perfect['mse'] == pytest.approx(0.0)


def test_eval_bag_topic_options_pick_the_topics(tmp_path, capsys):
    """
    `eval-bag --goal-topic` etc..

    A bag with two robots' goals side by side is an error naming both without the option (never a
    silent pick), and each robot's own MD with it; a truth recorded under another name is found by
    its relative name.
    """
    bag = write_bag(
        tmp_path / 'bag',
        [('a', (1, 1), (1, 1)), ('b', (5, 5), (5, 8))],
        names={'goal': '/robot1/goal_pose', 'truth': '/robot1/expected_goal'},
        other_goals={'/robot2/goal_pose': [(1, 4), (9, 8)]},
    )
    assert cli.main(['eval-bag', str(bag), '--truth-topic', 'expected_goal']) == 2
    err = capsys.readouterr().err
    assert '/robot1/goal_pose, /robot2/goal_pose' in err and '--goal-topic' in err
    for robot, md in (('robot1', (0 + 3) / 2), ('robot2', (3 + 4) / 2)):
        assert (
            cli.main(
                [
                    'eval-bag',
                    str(bag),
                    '--json',
                    '--goal-topic',
                    f'/{robot}/goal_pose',
                    '--truth-topic',
                    'expected_goal',
                ]
            )
            == 0
        )
        out = json.loads(capsys.readouterr().out)
        assert out['topics']['goal'] == f'/{robot}/goal_pose'
        assert out['topics']['truth'] == '/robot1/expected_goal'
        assert out['n'] == 2 and out['md'] == pytest.approx(md), robot


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    assert cli.main(['eval-bag', str(tmp_path / 'missing')]) == 2
    assert 'not found' in capsys.readouterr().err
    junk = tmp_path / 'junk.txt'
    junk.write_text('not a bag')
    assert cli.main(['eval-bag', str(junk)]) == 2
    assert 'not a rosbag2 bag' in capsys.readouterr().err
    no_map = write_bag(tmp_path / 'nomap', [('a', (1, 1), (1, 1))], skip=('map',))
    assert cli.main(['eval-bag', str(no_map)]) == 2
    err = capsys.readouterr().err
    assert 'entity_map' in err and err.count('\n') == 1
    truncated = write_bag(tmp_path / 'trunc', [('a', (1, 1), (1, 1))] * 50)
    mcap = next(truncated.glob('*.mcap'))
    mcap.write_bytes(mcap.read_bytes()[: mcap.stat().st_size // 2])
    assert cli.main(['eval-bag', str(truncated)]) == 2
    assert 'spatial-grounding: error:' in capsys.readouterr().err
