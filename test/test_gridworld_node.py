# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The gridworld node over real DDS.

It publishes an episode (map in the OccupancyGrid orientation, instruction, truth), moves on
actions, walks to a goal_pose, and answers bad input with a warning diagnostic while it keeps
serving. Plus the closed-loop demo.

Every wait is for an event (a message, a match, a service), with a generous timeout that only
fails a test when the event never comes; the probe publishes only once the node's subscriptions
have matched its publishers, and counts on stream topics only once it is matched to the node's
publishers. No assertion bounds an elapsed time.
"""

import os
import secrets
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import OccupancyGrid
import numpy as np
import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from spatial_grounding_ros.core import world
from spatial_grounding_ros.data.generator import generate
from spatial_grounding_ros.ros import convert
from spatial_grounding_ros.ros.gridworld_node import GridWorldNode
from spatial_grounding_ros.ros.qos import LATCHED, STREAM
from std_msgs.msg import Bool, Float32, Float32MultiArray, Int32, String
from std_srvs.srv import Trigger


@pytest.fixture
def ros():
    context = rclpy.Context()
    rclpy.init(context=context)
    executor = SingleThreadedExecutor(context=context)
    nodes = []

    def make(cls, *args, **kwargs):
        node = cls(*args, context=context, **kwargs)
        nodes.append(node)
        executor.add_node(node)
        return node

    yield make, executor
    for node in nodes:
        executor.remove_node(node)
        node.destroy_node()
    rclpy.shutdown(context=context)


# a namespace of this run's own: runs that share a ROS_DOMAIN_ID (one of 100) never meet
NAMESPACE = f'/gw_test_{os.getpid()}_{secrets.token_hex(3)}'


class Probe(rclpy.node.Node):
    def __init__(self, context):
        super().__init__('probe', namespace=NAMESPACE, context=context)
        self.got = {
            k: []
            for k in (
                'map',
                'instruction',
                'pose',
                'reward',
                'terminated',
                'goal',
                'values',
                'diag',
            )
        }
        sub = self.create_subscription
        sub(OccupancyGrid, 'entity_map', self.got['map'].append, LATCHED)
        sub(String, 'instruction', self.got['instruction'].append, LATCHED)
        sub(PoseStamped, 'true_goal', self.got['goal'].append, LATCHED)
        sub(Float32MultiArray, 'true_value_map', self.got['values'].append, LATCHED)
        # not latched: what the node sends before these match is lost to the probe
        self.streams = [
            sub(PoseStamped, 'agent_pose', self.got['pose'].append, STREAM),
            sub(Float32, 'reward', self.got['reward'].append, STREAM),
            sub(Bool, 'terminated', self.got['terminated'].append, STREAM),
        ]
        self.diagnostics = sub(DiagnosticArray, '/diagnostics', self.on_diagnostics, 10)
        self.action = self.create_publisher(Int32, 'action', STREAM)
        self.goal = self.create_publisher(PoseStamped, 'goal_pose', 10)
        self.next = self.create_client(Trigger, 'next_episode')
        self.reset = self.create_client(Trigger, 'reset_episode')

    def connected(self) -> bool:
        """
        Tell whether the gridworld and this probe are matched both ways.

        The node's action and goal_pose subscriptions have matched the probe's publishers (a
        message published before that is lost), the probe's stream subscriptions and its
        /diagnostics subscription have matched the node's publishers, and both services are
        there.
        """
        diagnostics = self.get_publishers_info_by_topic('/diagnostics')
        return (
            self.action.get_subscription_count() > 0
            and self.goal.get_subscription_count() > 0
            and all(s.get_publisher_count() > 0 for s in self.streams)
            and any(
                p.node_namespace == NAMESPACE and p.node_name == 'gridworld' for p in diagnostics
            )
            and self.diagnostics.get_publisher_count() >= len(diagnostics)
            and self.next.service_is_ready()
            and self.reset.service_is_ready()
        )

    def on_diagnostics(self, msg):
        # /diagnostics is global: keep this namespace's gridworld only
        if msg.status and msg.status[0].name.startswith(f'{NAMESPACE}/gridworld:'):
            self.got['diag'].append(msg)


def spin_until(executor, cond, timeout=60.0):
    """Spin until `cond()` holds; fail only if it never does within the (generous) timeout."""
    end = time.monotonic() + timeout
    while not cond():
        assert time.monotonic() < end, f'waited {timeout:g} s and it never happened'
        executor.spin_once(timeout_sec=0.02)


def test_episode_actions_goal_walk_and_bad_input(ros):
    make, executor = ros
    params = [
        Parameter('source', value='generator-local'),
        Parameter('episodes', value=3),
        Parameter('seed', value=5),
        Parameter('step_period', value=0.01),
        Parameter('resolution', value=0.5),
        Parameter('origin_x', value=2.0),
    ]
    gw = make(GridWorldNode, namespace=NAMESPACE, parameter_overrides=params)
    probe = make(Probe)
    got = probe.got
    spin_until(
        executor, lambda: got['map'] and got['instruction'] and got['goal'] and got['values']
    )
    spin_until(executor, probe.connected)
    # agent poses are not latched: restart the episode now that the probe listens
    n_pose = len(got['pose'])
    future = probe.reset.call_async(Trigger.Request())
    spin_until(executor, lambda: future.done() and len(got['pose']) > n_pose)
    data = generate(3, seed=5, mode='local')
    # the latched episode: data-set row 0 is the map's top (largest y) row
    grid = convert.occupancy_grid_to_grid(got['map'][-1], 10**6)
    assert np.array_equal(grid, data.grids[0])
    assert list(got['map'][-1].data[:10]) == list(data.grids[0][-1])  # grid row 0 = south
    assert got['instruction'][-1].data == data.instructions[0]
    info = got['map'][-1].info
    assert convert.point_to_cell(
        got['goal'][-1].pose.position.x, got['goal'][-1].pose.position.y, info
    ) == tuple(data.goals[0])
    np.testing.assert_allclose(
        convert.float32_multiarray_to_value_map(got['values'][-1]), data.values[0], atol=1e-5
    )

    def cell(pose):
        return convert.point_to_cell(pose.pose.position.x, pose.pose.position.y, info)

    # an action moves the agent and reports the entered cell's reward
    start = cell(got['pose'][-1])
    probe.action.publish(Int32(data=3))
    spin_until(executor, lambda: got['reward'] and got['terminated'] and len(got['pose']) >= 2)
    moved = world.step_cell(start, 3, (10, 10))
    assert cell(got['pose'][-1]) == moved
    assert got['reward'][-1].data == pytest.approx(data.rewards[0][moved])

    # bad input: warnings on /diagnostics, nothing moves
    n_pose = len(got['pose'])
    probe.action.publish(Int32(data=7))
    far = convert.cell_to_pose((0, 0), info, 'map', gw.get_clock().now().to_msg())
    far.pose.position.x = -100.0
    probe.goal.publish(far)
    wrong = convert.cell_to_pose((0, 0), info, 'odom', gw.get_clock().now().to_msg())
    probe.goal.publish(wrong)
    spin_until(
        executor,
        lambda: len([d for d in got['diag'] if d.status[0].level == DiagnosticStatus.WARN]) >= 3,
    )
    messages = ' | '.join(d.status[0].message for d in got['diag'])
    assert 'action 7 ignored' in messages and 'outside' in messages and "'odom'" in messages
    assert len(got['pose']) == n_pose

    # a goal_pose is walked to, cell by cell
    future = probe.next.call_async(Trigger.Request())
    spin_until(executor, future.done)
    spin_until(executor, lambda: got['instruction'][-1].data == data.instructions[1])
    target = tuple(int(x) for x in data.goals[1])
    probe.goal.publish(convert.cell_to_pose(target, info, 'map', gw.get_clock().now().to_msg()))
    spin_until(executor, lambda: got['terminated'] and got['terminated'][-1].data)
    assert cell(got['pose'][-1]) == target
    assert got['reward'][-1].data == pytest.approx(data.rewards[1][target])


def test_sim_time_without_clock_still_starts_and_walks(ros):
    """
    use_sim_time:=true with nothing on /clock: the node's timers run on steady time.

    The first episode waits for a subscriber (a timer) and a goal_pose is walked to (a timer);
    ROS-time timers would never fire here. Stamps follow the node's clock: sim time 0.
    """
    make, executor = ros
    params = [
        Parameter('use_sim_time', value=True),
        Parameter('source', value='generator-local'),
        Parameter('episodes', value=2),
        Parameter('seed', value=5),
        Parameter('step_period', value=0.01),
        Parameter('start_after_subscribers', value=1),
    ]
    make(GridWorldNode, namespace=NAMESPACE, parameter_overrides=params)
    probe = make(Probe)
    got = probe.got
    # the latched episode shows that the first one started (the start timer fired); its start
    # pose is not latched, and the walk's poses come once the probe is matched
    spin_until(executor, lambda: got['instruction'] and got['map'] and got['goal'])
    spin_until(executor, probe.connected)
    assert got['map'][-1].header.stamp.sec == 0 and got['map'][-1].header.stamp.nanosec == 0
    info = got['map'][-1].info
    target = convert.point_to_cell(
        got['goal'][-1].pose.position.x, got['goal'][-1].pose.position.y, info
    )
    probe.goal.publish(convert.cell_to_pose(target, info, 'map', got['goal'][-1].header.stamp))
    spin_until(executor, lambda: got['terminated'] and got['terminated'][-1].data)
    last = got['pose'][-1].pose.position
    assert convert.point_to_cell(last.x, last.y, info) == target


def test_closed_loop_demo_on_sim_time(tmp_path):
    """The demo with use_sim_time:=true on both nodes (no /clock) reaches its goals."""
    from spatial_grounding_ros.ros.demo import run_demo

    summary = run_demo(
        tmp_path,
        episodes=2,
        seed=1,
        data_dir=str(tmp_path / 'no_data'),
        step_period=0.02,
        use_sim_time=True,
    )
    assert summary['episodes'] == 2
    assert summary['from_bag']['hit'] == 1.0, summary['per_episode']
    for episode in summary['per_episode']:
        assert episode['end'] == episode['goal'], episode  # walked to each goal_pose


def test_closed_loop_demo(tmp_path, capsys):
    """
    Three episodes through the real processes, each goal_pose on the cell the instruction names.

    The grounder hears the first instruction as
    it is published (no episode is restarted): the bag holds exactly one instruction and one
    goal per episode. Its agent poses carry a publish time and a later log time, although this
    process drew a PNG between episodes (test_bag_recorder.py holds the recorder's thread to
    show that the log time is the reception, not when the callback ran).
    """
    from spatial_grounding_ros.ros.demo import run_demo

    summary = run_demo(
        tmp_path, episodes=3, seed=1, data_dir=str(tmp_path / 'no_data'), step_period=0.02
    )
    out = capsys.readouterr().out
    assert summary['episodes'] == 3
    # the shipped default sends goal_pose to the named cell (98.5% of generated 10x10
    # instructions, README suite table): all three seeded episodes ("reach cell with circle",
    # "... to top right of triangle", "... two below diamond"), as the bag records them.
    # (Reaching the goal is weaker: a walk to the triangle crosses the cell below it.)
    assert summary['from_bag']['hit'] == 1.0, summary['per_episode']
    # each episode's outcome is its own: terminated exactly when it ended on the true goal
    for episode in summary['per_episode']:
        assert episode['reached'] == (episode['end'] == episode['truth']), episode
    assert [line[:3] for line in out.splitlines() if line.startswith('[')] == ['[0]', '[1]', '[2]']
    assert (tmp_path / 'episode_0.png').stat().st_size > 1000
    assert summary['from_bag']['n'] == 3 and summary['from_bag']['unanswered'] == 0
    assert summary['from_bag']['md'] == pytest.approx(summary['md'])
    assert 'pq' in summary['from_bag']
    recorded = {topic.rsplit('/', 1)[1]: n for topic, n in summary['recorded'].items()}
    assert recorded['instruction'] == 3 and recorded['goal_pose'] == 3, recorded
    assert recorded['agent_pose'] == recorded['reward'] + 3  # a start pose per episode

    make_reader = pytest.importorskip('mcap.reader', reason='pip install mcap').make_reader
    [mcap_file] = (tmp_path / 'demo_bag').glob('*.mcap')
    with open(mcap_file, 'rb') as stream:
        times = [
            (m.publish_time, m.log_time)
            for _, c, m in make_reader(stream).iter_messages()
            if c.topic.endswith('/agent_pose')
        ]
    assert times and all(0 < sent <= logged for sent, logged in times), times


@pytest.mark.parametrize(
    'parameter, needle',
    [
        ('step_period:=-1.0', 'parameter step_period must be 0.001..60, got -1.0'),
        ('step_period:=1', 'parameter step_period must be a double (write 5.0, not 5), got an'),
        ('source:=nowhere', 'parameter source must be one of generator, generator-local'),
        ('seed:=abc', "parameter seed must be an integer, got a string 'abc'"),
        ('frame_id:=""', 'parameter frame_id must not be empty'),
        ('source:=isi', 'data file not found'),  # a task whose data is not in data_dir
    ],
)
def test_bad_start_up_input_is_one_error_line_and_exit_1(tmp_path, parameter, needle):
    from pathlib import Path
    import subprocess
    import sys

    exe = Path(sys.executable).parent / 'gridworld'
    if not exe.is_file():
        pytest.skip(f'{exe} is not installed (pip install -e . makes it)')
    result = subprocess.run(
        [
            str(exe),
            '--ros-args',
            '-r',
            f'__ns:={NAMESPACE}_bad',
            '-p',
            parameter,
            '-p',
            f'data_dir:={tmp_path / "no_data"}',
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 1, result.stderr
    err = result.stderr
    assert err.splitlines() == [err.strip()] and err.startswith('gridworld: error: '), err
    assert needle in err, err
