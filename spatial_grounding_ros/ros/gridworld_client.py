# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
A client of the gridworld node with GridWorldEnv's interface: training/rl.py runs on it unchanged.

reset() calls next_episode and reads entity_map, instruction and agent_pose; step() publishes an
action and waits for that move's agent_pose, reward and terminated. Observations and the 5-tuple
of step() are GridWorldEnv's; the world's RNG is the node's (its `seed` parameter), so reset()
takes no seed and no options.

Messages of different topics may arrive in any order, so the client pairs them by count:
the node publishes exactly one agent_pose, reward and terminated per move.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import time

from geometry_msgs.msg import PoseStamped
from gymnasium import spaces
from nav_msgs.msg import OccupancyGrid
import rclpy
from rclpy.node import Node
from std_msgs.msg import Bool, Float32, Int32, String
from std_srvs.srv import Trigger

from . import convert
from .processes import stop_processes
from .qos import LATCHED, STREAM
from ..core import topics
from ..core.world import ACTIONS
from ..training.env import observation_space

NEXT_EPISODE_ATTEMPTS = 3  # requests of one reset(), each given a third of the timeout


class GridWorldClient(Node):
    """
    GridWorldEnv's interface on a gridworld node's topics under `namespace`.

    It subscribes to the node's topics and counts every message; `observation_space` is the
    space of the episodes the node serves (env.observation_space of them), `action_space` the
    four moves, as GridWorldEnv's.
    """

    def __init__(
        self,
        namespace: str,
        step_limit: int,
        observation_space: spaces.Dict,
        timeout: float = 10.0,
    ):
        super().__init__('gridworld_client', namespace=namespace)
        self.step_limit, self.timeout = step_limit, timeout
        self.observation_space = observation_space
        self.counts = {'map': 0, 'instruction': 0, 'pose': 0, 'reward': 0, 'terminated': 0}
        self.map_msg: OccupancyGrid | None = None
        self.instruction = ''
        self.poses: list[PoseStamped] = []
        self.rewards: list[float] = []
        self.terminals: list[bool] = []
        self.streams = [
            self.create_subscription(OccupancyGrid, topics.ENTITY_MAP, self.on_map, LATCHED),
            self.create_subscription(String, topics.INSTRUCTION, self.on_instruction, LATCHED),
            self.create_subscription(PoseStamped, topics.AGENT_POSE, self.on_pose, STREAM),
            self.create_subscription(Float32, topics.REWARD, self.on_reward, STREAM),
            self.create_subscription(Bool, topics.TERMINATED, self.on_terminated, STREAM),
        ]
        self.action_pub = self.create_publisher(Int32, topics.ACTION, STREAM)
        self.action_space = spaces.Discrete(len(ACTIONS))
        self.next_client = self.create_client(Trigger, topics.NEXT_EPISODE)
        self.steps = 0
        self.done = True

    def on_map(self, msg):
        self.map_msg = msg
        self.counts['map'] += 1

    def on_instruction(self, msg):
        self.instruction = msg.data
        self.counts['instruction'] += 1

    def on_pose(self, msg):
        self.poses.append(msg)
        self.counts['pose'] += 1

    def on_reward(self, msg):
        self.rewards.append(float(msg.data))
        self.counts['reward'] += 1

    def on_terminated(self, msg):
        self.terminals.append(bool(msg.data))
        self.counts['terminated'] += 1

    def wait_for(self, what: str, condition, timeout: float | None = None) -> None:
        timeout = self.timeout if timeout is None else timeout
        deadline = time.monotonic() + timeout
        while not condition():
            if time.monotonic() > deadline:
                raise TimeoutError(
                    f'no {what} from the gridworld node within {timeout:g} s '
                    f'(is it running in namespace {self.get_namespace()!r}?)'
                )
            rclpy.spin_once(self, timeout_sec=0.05)

    def matched(self) -> bool:
        """Return whether every topic with the node has matched, both ways."""
        return self.action_pub.get_subscription_count() > 0 and all(
            subscription.get_publisher_count() > 0 for subscription in self.streams
        )

    def observation(self) -> dict:
        pose = self.poses[-1].pose.position
        agent = convert.point_to_cell(pose.x, pose.y, self.map_msg.info)
        grid = convert.occupancy_grid_to_grid(self.map_msg, max_cells=10**7)
        return {'grid': grid, 'instruction': self.instruction, 'agent': agent}

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[dict, dict]:
        if seed is not None or options:
            raise ValueError(
                "the gridworld node's episodes are seeded by its seed parameter and chosen by "
                'its services: reset() takes no seed or options'
            )
        self.wait_for('next_episode service', lambda: self.next_client.service_is_ready())
        # volatile topics drop what is published before both ends match: the episode's pose
        # (and a step's action) would be lost to a node that answered the service first. And
        # the node's current episode (latched map and instruction: it plays one from its
        # start) must be in before the count, or it would pass for the next one
        self.wait_for(
            'matched topics',
            lambda: self.matched() and self.counts['map'] and self.counts['instruction'],
        )
        before = dict(self.counts)
        episode_topics = ('map', 'instruction', 'pose')  # a new episode republishes these

        def heard_back():
            return future.done() or any(self.counts[k] > before[k] for k in episode_topics)

        # The episode's messages, not only the service's answer, say that it started: Fast DDS
        # can report a service ready before the server has matched the client's response
        # reader, and then the answer is lost although the episode began. A request that gets
        # neither an answer nor a message is sent again.
        for attempt in range(NEXT_EPISODE_ATTEMPTS):
            future = self.next_client.call_async(Trigger.Request())
            try:
                self.wait_for(
                    'answer to next_episode', heard_back, self.timeout / NEXT_EPISODE_ATTEMPTS
                )
                break
            except TimeoutError:
                if attempt + 1 == NEXT_EPISODE_ATTEMPTS:
                    raise
                self.get_logger().warning('next_episode unanswered: sending it again')
        self.wait_for(
            'episode start', lambda: all(self.counts[k] > before[k] for k in episode_topics)
        )
        self.steps, self.done = 0, False
        return self.observation(), {'steps': 0}

    def step(self, action: int):
        if self.done:
            raise RuntimeError('the episode is over: call reset() first')
        before = dict(self.counts)
        self.action_pub.publish(Int32(data=int(action)))
        self.wait_for(
            'move result',
            lambda: all(self.counts[k] > before[k] for k in ('pose', 'reward', 'terminated')),
        )
        self.steps += 1
        reward, terminated = self.rewards[-1], self.terminals[-1]
        truncated = not terminated and self.steps >= self.step_limit
        self.done = terminated or truncated
        return self.observation(), reward, terminated, truncated, {'steps': self.steps}


@contextlib.contextmanager
def ros_envs(task: str, data_dir: str, train, cfg, seed: int):
    """
    Start a gridworld node process serving `task`'s train split; yield [a client of it].

    A generated task serves the same worlds as `train`. The node runs in a namespace of its
    own (this process's id), so parallel runs never share topics; it is stopped on exit.
    """
    namespace = f'/rl_{os.getpid()}'
    step_limit = cfg.step_limit or 5 * max(train.grids.shape[1:])
    params = {
        'source': task,
        'split': 'train',
        'data_dir': str(data_dir),
        'episodes': len(train),
        'seed': seed,
        'order': 'random',
        'step_limit': step_limit + 1,
    }  # the client cuts episodes off itself
    cmd = [
        sys.executable,
        '-m',
        'spatial_grounding_ros.ros.gridworld_node',
        '--ros-args',
        '-r',
        f'__ns:={namespace}',
        '-r',
        topics.DIAGNOSTICS_INTO_NAMESPACE,
    ]
    for k, v in params.items():
        cmd += ['-p', f'{k}:={v}']
    node_process = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    started_here = not rclpy.ok()
    if started_here:
        rclpy.init()
    space = observation_space(train.grids.shape[1:], len(train.entities), train.instructions)
    client = GridWorldClient(namespace, step_limit, space, timeout=60.0)
    try:
        yield [client]
    finally:
        client.destroy_node()
        if started_here:
            rclpy.try_shutdown()
        stop_processes(node_process)
