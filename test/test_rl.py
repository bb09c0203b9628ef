# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
RL by fitted value iteration.

The regression target follows the value convention, only visited cells are regressed, a tiny run
beats the untrained model on the same maps, and --via-ros, through a real gridworld node process,
learns exactly what the in-process loop does.
"""

import json

import numpy as np
import pytest
from spatial_grounding_ros import cli
from spatial_grounding_ros.core.text import tokenize, Vocabulary
from spatial_grounding_ros.data.augment import mirror
from spatial_grounding_ros.data.generator import generate
from spatial_grounding_ros.models.checkpoints import load_checkpoint
from spatial_grounding_ros.studies.reproduce import reproduce_rl
from spatial_grounding_ros.training.env import GridWorldEnv, load_episodes
from spatial_grounding_ros.training.rl import (
    act,
    fitted_value_step,
    goal_loss,
    ReplayBuffer,
    resolve_config,
    RLConfig,
    train_rl,
)
import torch


class ConstantMap(torch.nn.Module):
    """A 'model' whose predicted map is a fixed array (for checking the regression target)."""

    def __init__(self, values):
        super().__init__()
        self.values = torch.nn.Parameter(torch.as_tensor(values, dtype=torch.float32))

    def forward(self, grids, tokens):
        return self.values.expand(len(grids), -1, -1)


def test_act_is_greedy_over_the_predicted_map():
    values = np.zeros((5, 5))
    values[2, 3] = 1.0
    rng = np.random.default_rng(0)
    assert act(values, (2, 2), 0.0, rng) == 3  # right
    assert act(values, (1, 3), 0.0, rng) == 1  # down


def test_fitted_value_target_uses_own_reward_and_target_max():
    data = generate(1, seed=0)
    grid, text = data.grids[0], data.instructions[0]
    buffer = ReplayBuffer((10, 10))
    i = buffer.map_id(grid, text)
    buffer.add(i, (0, 0), 3, -1.0, (0, 1), False)  # entered a puddle cell
    buffer.add(i, (4, 4), 1, 3.0, (5, 4), True)  # entered the goal
    target_values = np.arange(100, dtype=np.float32).reshape(10, 10) / 100
    online = ConstantMap(np.zeros((10, 10)))
    target = ConstantMap(target_values)
    vocab = Vocabulary.build([text])
    opt = torch.optim.SGD(online.parameters(), lr=0.5)
    cfg = RLConfig(batch_maps=1, gamma=0.9, priority=0.0, goal_weight=0.0)
    fitted_value_step(online, {}, target, vocab, buffer, opt, cfg, np.random.default_rng(0))
    # loss = mean over the 2 visited cells of (pred - target)^2; SGD step lr 0.5 moves each
    # visited cell by 0.5 * 2 * (target - pred) / 2 = 0.5 * target, the rest not at all
    moved = online.values.detach().numpy()
    expected_puddle = -1.0 + 0.9 * max(
        target_values[1, 1], target_values[0, 0], target_values[0, 2], target_values[0, 1]
    )
    assert moved[0, 1] == pytest.approx(0.5 * expected_puddle, abs=1e-5)
    assert moved[5, 4] == pytest.approx(0.5 * 3.0, abs=1e-5)  # terminal: no bootstrap
    untouched = np.ones((10, 10), bool)
    untouched[0, 1] = untouched[5, 4] = False
    assert np.all(moved[untouched] == 0)


def test_goal_loss_points_only_maps_with_a_found_goal_at_it():
    """The cross-entropy of the found goal cells; maps with no goal found add nothing."""
    pred = torch.zeros(3, 4)
    pred[0, 1] = 1.0
    goals = torch.zeros(3, 4, dtype=torch.bool)
    goals[0, 1] = True  # found, and already the highest cell
    goals[1, 2] = goals[1, 3] = True  # two goal cells found in a flat map
    loss = goal_loss(pred, goals, 2.0)
    first = -torch.log_softmax(2.0 * pred[0], 0)[1]
    second = -torch.log(torch.tensor(0.5))  # half the mass on the two goal cells
    assert loss.item() == pytest.approx(((first + second) / 2).item(), abs=1e-6)
    assert goal_loss(pred, torch.zeros(3, 4, dtype=torch.bool), 2.0).item() == 0.0


def test_goal_weight_defaults_to_the_tasks():
    """Check the task defaults: PuddleWorld and generated worlds 0.3, ISI 0.05; one given wins."""
    shape = (10, 10)
    assert resolve_config(RLConfig(), 'pw-local', shape).goal_weight == 0.3
    assert resolve_config(RLConfig(), 'generator-local', shape).goal_weight == 0.3
    assert resolve_config(RLConfig(), 'isi', (13, 13)).goal_weight == 0.05
    assert resolve_config(RLConfig(goal_weight=1.0), 'isi', (13, 13)).goal_weight == 1.0


def test_mirror_images_record_the_mirrored_worlds_rewards():
    """
    Check that random play on one map fills its three mirror images correctly.

    Random play on one map fills its three mirror images with exactly the rewards and
    goal of the mirrored world (augment.mirror), and swaps the instruction's directions.
    """
    data = generate(3, seed=4, mode='local')
    env = GridWorldEnv(data, step_limit=60, order='sequential')
    buffer = ReplayBuffer((10, 10), mirrors=True)
    rng = np.random.default_rng(0)
    for _ in range(3):
        obs, _ = env.reset()
        i = buffer.map_id(obs['grid'], obs['instruction'])
        done = False
        while not done:
            s = obs['agent']
            obs, r, terminated, truncated, _ = env.step(int(rng.integers(4)))
            buffer.add(i, s, 0, r, obs['agent'], terminated)
            done = terminated or truncated
    assert buffer.n_observed == 3 and len(buffer.grids) == 12
    lr, ud = mirror(data, 2), mirror(data, 1)
    images = {'lr': lr, 'ud': ud, 'both': mirror(lr, 1)}
    for k in range(3):
        ids = [k * 4 + j for j in range(4)]
        for i, world_set in zip(ids, [data, images['lr'], images['ud'], images['both']]):
            assert np.array_equal(buffer.grids[i], world_set.grids[k])
            assert buffer.instructions[i] == world_set.instructions[k] or i == ids[0]
            seen = buffer.visited[i]
            assert seen.sum() == buffer.visited[ids[0]].sum() > 0
            assert np.array_equal(buffer.reward[i][seen], world_set.rewards[k][seen])
            assert np.array_equal(buffer.terminal[i][seen], world_set.terminal[k][seen])
    if 'left' in tokenize(data.instructions[0]):
        assert 'right' in tokenize(buffer.instructions[1])


def test_tiny_run_learns_and_writes_a_checkpoint(tmp_path):
    """
    Check that 1024 episodes lift PQ well above the untrained model.

    1024 episodes (a few seconds) lift PQ on 30 unseen generated maps well above the same
    model untrained: the same run with 0 episodes, which starts from the same seeded weights
    and evaluates on the same maps (PQ about 0 untrained, 0.77 trained). MSE must fall too:
    PQ alone also rises when only the puddles' -1 is learned (with the goal's +3 never
    regressed, PQ still reached 0.73 while MSE rose from 1.70 to 1.83; trained: 1.20). The
    regression alone (goal weight 0): the goal cross-entropy, sharpening the maps' peaks, costs
    MSE (docs/rl.md), and at 1024 episodes it leaves MSE 2.30 against 2.41 untrained.
    """
    train, test = generate(60, seed=1, mode='local'), generate(30, seed=2, mode='local')
    runs = {}
    for episodes in (0, 1024):
        cfg = RLConfig(
            episodes=episodes, envs=64, updates_per_round=8, batch_maps=32, seed=0, goal_weight=0
        )
        runs[episodes] = train_rl(
            'generator-local',
            't-cnn',
            '',
            tmp_path / str(episodes),
            cfg,
            train,
            test,
            progress=False,
        )
    (_, untrained), (path, summary) = runs[0], runs[1024]
    assert untrained['transitions'] == 0 and untrained['test']['n'] == summary['test']['n'] == 30
    assert summary['episodes'] == 1024 and summary['maps_seen'] <= 60
    assert summary['transitions'] >= 1024
    trained, before = summary['test'], untrained['test']
    assert trained['pq'] > before['pq'] + 0.4, (trained, before)
    assert trained['mse'] < before['mse'] - 0.3, (trained, before)
    assert trained['md'] < before['md']
    loaded = load_checkpoint(path)
    assert loaded.name == 't-cnn' and loaded.header['training'].startswith('rl')


def test_rl_train_via_ros_equals_the_in_process_run(tmp_path, capsys):
    """
    Check that `rl-train --via-ros` learns exactly what the in-process loop learns.

    `rl-train --via-ros` (episodes from a gridworld node process, over topics) learns
    exactly what the in-process loop learns from the same episodes: the node's environment
    is seeded with --seed and plays one episode when it starts (which the client skips with
    next_episode), so an in-process environment seeded alike, after one reset, serves the
    same maps, starts and rewards; every transition, metric and weight must then agree.
    """
    code = cli.main(
        [
            'rl-train',
            '--task',
            'generator-local',
            '--model',
            't-cnn',
            '--via-ros',
            '--episodes',
            '6',
            '--step-limit',
            '10',
            '--generated',
            '20',
            '--out',
            str(tmp_path / 'ros'),
            '--quiet',
        ]
    )
    assert code == 0
    via_ros = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert via_ros['episodes'] == 6
    assert 6 <= via_ros['transitions'] <= 60

    train = load_episodes('generator-local', n=20, seed=0)  # as rl-train makes them
    test = load_episodes('generator-local', n=50, seed=1000)
    env = GridWorldEnv(train, step_limit=10)
    env.reset(seed=0)  # the node's first episode, seeded as the node seeds it
    cfg = RLConfig(episodes=6, step_limit=10, seed=0, threads=1)
    path, in_process = train_rl(
        'generator-local',
        't-cnn',
        '',
        tmp_path / 'local',
        cfg,
        train,
        test,
        envs=[env],
        progress=False,
    )
    for key in ('episodes', 'transitions', 'maps_seen', 'updates', 'test', 'rl_config'):
        assert via_ros[key] == in_process[key], key
    ros_weights = load_checkpoint(
        tmp_path / 'ros' / 'rl_generator-local_t-cnn.pt'
    ).model.state_dict()
    for name, weights in load_checkpoint(path).model.state_dict().items():
        torch.testing.assert_close(ros_weights[name], weights, rtol=0, atol=0)


def test_reproduce_rl_keeps_rows_of_earlier_runs(data_dir, tmp_path):
    """A run over some tasks replaces its own rows of rl.json and keeps the others."""
    earlier = {
        'task': 'isi',
        'model': 't-cnn',
        'test': {'pq': 0.5, 'md': 3.0, 'mse': 1.0, 'n': 1},
        'episodes': 1,
        'train_seconds': 1.0,
    }
    (tmp_path / 'rl.json').write_text(json.dumps({'results': [earlier]}))
    reproduce_rl(
        str(data_dir),
        str(tmp_path),
        tasks=('pw-local',),
        models=('t-cnn',),
        scale=1e-4,
        jobs=1,
        checkpoints=str(tmp_path),
    )
    rows = json.loads((tmp_path / 'rl.json').read_text())['results']
    assert [(r['task'], r['model']) for r in rows] == [('pw-local', 't-cnn'), ('isi', 't-cnn')]
    assert rows[0]['episodes'] == 1 and rows[0]['test']['n'] == 399
    table = (tmp_path / 'rl.md').read_text()
    assert '| pw-local | t-cnn |' in table and '| isi | t-cnn | 0.50 | 0.74 |' in table


def test_ros_client_has_the_environment_spaces():
    """
    The ROS client is GridWorldEnv's interface: the same spaces, observations inside them.

    (Gymnasium's check_env cannot run on it: its episodes are seeded by the node's parameter,
    so reset(seed=) is refused.)
    """
    from spatial_grounding_ros.data.datasets import DEFAULT_DATA
    from spatial_grounding_ros.ros.gridworld_client import ros_envs

    train = load_episodes('generator-local', n=20, seed=0)
    env = GridWorldEnv(train, step_limit=10)
    with ros_envs('generator-local', DEFAULT_DATA, train, RLConfig(step_limit=10), 0) as [client]:
        assert client.observation_space == env.observation_space
        assert client.action_space == env.action_space
        obs, _ = client.reset()
        assert client.observation_space.contains(obs), obs
        for action in range(client.action_space.n):
            obs, _, terminated, truncated, _ = client.step(action)
            assert client.observation_space.contains(obs), obs
            if terminated or truncated:
                break
