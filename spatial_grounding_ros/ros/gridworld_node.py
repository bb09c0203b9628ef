# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The gridworld node (`ros2 run spatial_grounding_ros gridworld`).

A simulated PuddleWorld/ISI-style world over topics, a thin adapter over env.GridWorldEnv.

Each episode publishes the entity map and the instruction (transient local, what the grounder
node listens to), the agent's start pose, and, for evaluation only, the true goal, the true
value map and the reward map. The agent moves on discrete `action`s, or walks toward a
received `goal_pose` one cell per `step_period` (a shortest path, going round puddles when
that is no longer). After every move it publishes the agent pose, the reward of the cell
entered and whether that ended the episode. Parameters: PARAMETERS below (and
config/gridworld.yaml); topics are relative, remap them with -r. Bad input gets a warning and
a diagnostic on /diagnostics, and the node keeps serving.
"""

from __future__ import annotations

import sys
from typing import NoReturn

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import OccupancyGrid, Path
import numpy as np
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from std_msgs.msg import Bool, Float32, Float32MultiArray, Header, Int32, String
from std_srvs.srv import Trigger

from . import convert
from .node_support import declare_parameters, Param, report, spin
from .qos import LATCHED, STREAM
from ..core import topics
from ..core import world
from ..core.tasks import TASKS
from ..data.datasets import DEFAULT_DATA, SPLITS
from ..training.env import GENERATED, GridWorldEnv, load_episodes

NODE_NAME = 'gridworld'

# Everything here shapes the episodes or the timer made at start-up: read-only.
PARAMETERS = (
    Param(
        'source',
        'generator',
        'where episodes come from: generator (mixed local/global), generator-local, '
        "generator-global (the project's own worlds, no download), or a data-set task read "
        'from data_dir (its split)',
        read_only=True,
        choices=GENERATED + tuple(TASKS),
    ),
    Param(
        'split', 'test', 'data-set split of a task source', read_only=True, choices=tuple(SPLITS)
    ),
    Param(
        'data_dir',
        DEFAULT_DATA,
        'folder of the data sets (task sources only)',
        read_only=True,
        non_empty=True,
    ),
    Param(
        'episodes',
        20,
        'generated examples (generator sources only)',
        read_only=True,
        low=1,
        high=1000000,
    ),
    Param(
        'seed',
        0,
        'seed of the generated worlds and of the start cells',
        read_only=True,
        low=0,
        high=2**31 - 1,
    ),
    Param(
        'order',
        'sequential',
        'episode order: sequential goes through the examples in turn, random draws one',
        read_only=True,
        choices=('sequential', 'random'),
    ),
    Param(
        'step_limit',
        50,
        'moves per episode before it is cut off (truncated)',
        read_only=True,
        low=1,
        high=1000000,
    ),
    Param(
        'step_period',
        0.1,
        'seconds between moves when following a goal_pose',
        read_only=True,
        low=0.001,
        high=60.0,
    ),
    Param(
        'frame_id', 'map', 'frame of the published maps and poses', read_only=True, non_empty=True
    ),
    Param('resolution', 1.0, 'metres per cell', read_only=True, low=1e-6, high=1e6),
    Param(
        'origin_x', 0.0, 'map-frame x of the south-west corner', read_only=True, low=-1e9, high=1e9
    ),
    Param(
        'origin_y', 0.0, 'map-frame y of the south-west corner', read_only=True, low=-1e9, high=1e9
    ),
    Param(
        'start_after_subscribers',
        0,
        'publish the first episode only once `instruction` has this many matched '
        'subscriptions (a grounder, a recorder, ...), so each hears it live; 0: at start-up',
        read_only=True,
        low=0,
        high=1000,
    ),
)


class GridWorldNode(Node):
    """GridWorldEnv episodes over topics and services."""

    def __init__(self, **node_options):
        super().__init__(NODE_NAME, **node_options)
        declare_parameters(self, PARAMETERS)
        data = load_episodes(
            self.param('source'),
            self.param('split'),
            self.param('data_dir'),
            n=self.param('episodes'),
            seed=self.param('seed'),
        )
        self.env = GridWorldEnv(
            data, step_limit=self.param('step_limit'), order=self.param('order')
        )
        self.obstacles = np.isin(data.grids, data.entities.obstacles)
        self.info = convert.map_info(
            self.env.shape,
            self.param('resolution'),
            (self.param('origin_x'), self.param('origin_y')),
        )
        convert.check_map_info(self.info, max_cells=10**7)
        self.frame_id = self.param('frame_id')
        self.get_logger().info(
            f'{len(data)} episodes from {data.name}, {self.env.shape[0]}x{self.env.shape[1]} cells'
        )

        self.map_pub = self.create_publisher(OccupancyGrid, topics.ENTITY_MAP, LATCHED)
        self.instruction_pub = self.create_publisher(String, topics.INSTRUCTION, LATCHED)
        self.true_goal_pub = self.create_publisher(PoseStamped, topics.TRUE_GOAL, LATCHED)
        self.true_values_pub = self.create_publisher(
            Float32MultiArray, topics.TRUE_VALUE_MAP, LATCHED
        )
        self.true_rewards_pub = self.create_publisher(
            Float32MultiArray, topics.TRUE_REWARD_MAP, LATCHED
        )
        self.pose_pub = self.create_publisher(PoseStamped, topics.AGENT_POSE, STREAM)
        self.reward_pub = self.create_publisher(Float32, topics.REWARD, STREAM)
        self.terminated_pub = self.create_publisher(Bool, topics.TERMINATED, STREAM)
        self.diagnostics_pub = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS, 10)
        self.create_subscription(Int32, topics.ACTION, self.on_action, STREAM)
        self.create_subscription(PoseStamped, topics.GOAL_POSE, self.on_goal_pose, 10)
        # the grounder's goal_path: the rest of a sequence after goal_pose; empty: stop
        self.create_subscription(Path, topics.GOAL_PATH, self.on_goal_path, 10)
        self.next_goals: list[tuple[int, int]] = []  # a sequence's goals after path_goal
        self.create_service(Trigger, topics.RESET_EPISODE, self.on_reset)
        self.create_service(Trigger, topics.NEXT_EPISODE, self.on_next)
        self.path_policy: np.ndarray | None = None  # greedy actions toward a goal_pose
        self.path_goal: tuple[int, int] | None = None
        # The timers pace the simulation itself, so they run on steady time: with
        # use_sim_time:=true and nothing on /clock (this node is the simulation), ROS-time
        # timers would never fire and the walk and the first episode would wait forever.
        # Stamps still come from the node's clock (sim time when asked).
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.walk_timer = self.create_timer(
            self.param('step_period'), self.walk_step, clock=steady
        )
        self.start_timer = None
        if self.param('start_after_subscribers') == 0:
            self.start_episode(None)
        else:
            self.start_timer = self.create_timer(0.02, self.start_when_subscribed, clock=steady)

    def start_when_subscribed(self) -> None:
        if self.instruction_pub.get_subscription_count() >= self.param('start_after_subscribers'):
            self.destroy_timer(self.start_timer)
            self.start_timer = None
            if self.env.example < 0:  # no service call started one meanwhile
                self.start_episode(None)

    def param(self, name: str):
        return self.get_parameter(name).value

    def header(self) -> Header:
        return Header(stamp=self.get_clock().now().to_msg(), frame_id=self.frame_id)

    def publish_pose(self) -> None:
        self.pose_pub.publish(
            convert.cell_to_pose(
                self.env.agent, self.info, self.frame_id, self.get_clock().now().to_msg()
            )
        )

    def start_episode(self, example: int | None) -> None:
        """Reset the environment (the next episode, or `example` again) and publish it."""
        # the first episode seeds the environment (its start cells and random order)
        self.env.reset(
            seed=self.param('seed') if self.env.example < 0 else None,
            options=None if example is None else {'example': example},
        )
        self.path_policy = self.path_goal = None
        i, header = self.env.example, self.header()
        self.map_pub.publish(convert.grid_to_occupancy_grid(self.env.grid, header, self.info))
        self.true_goal_pub.publish(
            convert.cell_to_pose(self.env.goal, self.info, self.frame_id, header.stamp)
        )
        self.true_values_pub.publish(
            convert.value_map_to_float32_multiarray(self.env.data.values[i])
        )
        self.true_rewards_pub.publish(
            convert.value_map_to_float32_multiarray(self.env.data.rewards[i])
        )
        self.instruction_pub.publish(String(data=self.env.instruction))
        self.publish_pose()
        self.get_logger().info(f'episode {i}: {self.env.instruction!r}, agent at {self.env.agent}')

    def on_reset(self, request, response):
        self.start_episode(self.env.example if self.env.example >= 0 else None)
        response.success, response.message = True, f'episode {self.env.example} restarted'
        return response

    def on_next(self, request, response):
        self.start_episode(None)
        response.success, response.message = True, f'episode {self.env.example} started'
        return response

    def move(self, action: int) -> None:
        _, reward, terminated, truncated, _ = self.env.step(action)
        self.publish_pose()
        self.reward_pub.publish(Float32(data=reward))
        self.terminated_pub.publish(Bool(data=terminated))
        if terminated or truncated:
            self.path_policy = None
            self.get_logger().info(
                f'episode {self.env.example} '
                f'{"reached the goal" if terminated else "hit the step limit"}'
                f' after {self.env.steps} moves, return '
                f'{self.env.total_reward:g}'
            )

    def on_action(self, msg: Int32) -> None:
        if not 0 <= msg.data < len(world.ACTIONS):
            self.report(
                'action',
                DiagnosticStatus.WARN,
                f'action {msg.data} ignored: use 0..{len(world.ACTIONS) - 1} '
                f'({", ".join(world.ACTION_NAMES)})',
            )
            return
        if self.env.done:
            self.report(
                'action',
                DiagnosticStatus.WARN,
                f'action {msg.data} ignored: the episode is over (call next_episode '
                'or reset_episode)',
            )
            return
        self.path_policy = None  # an explicit action cancels a goal walk
        self.move(msg.data)

    def on_goal_pose(self, msg: PoseStamped) -> None:
        frame = msg.header.frame_id
        if frame and frame != self.frame_id:
            self.report(
                'goal_pose',
                DiagnosticStatus.WARN,
                f'goal_pose ignored: frame {frame!r} is not the map frame {self.frame_id!r}',
            )
            return
        p = msg.pose.position
        cell = convert.point_to_cell(p.x, p.y, self.info)
        if cell is None:
            self.report(
                'goal_pose',
                DiagnosticStatus.WARN,
                f'goal_pose ignored: ({p.x:g}, {p.y:g}) is outside the '
                f'{self.info.width}x{self.info.height} map',
            )
            return
        if self.env.done:
            self.report(
                'goal_pose',
                DiagnosticStatus.WARN,
                'goal_pose ignored: the episode is over (call next_episode)',
            )
            return
        self.walk_to(cell)
        self.next_goals = []
        self.report('goal_pose', DiagnosticStatus.OK, f'walking from {self.env.agent} to {cell}')

    def walk_to(self, cell: tuple[int, int]) -> None:
        self.path_policy = world.greedy_policy(self.path_values(cell))
        self.path_goal = cell

    def on_goal_path(self, msg: Path) -> None:
        """Stop the agent on an empty path (a stop); else walk its goals after goal_pose next."""
        if not msg.poses:
            self.path_policy, self.next_goals = None, []
            self.report('goal_path', DiagnosticStatus.OK, f'stopped at {self.env.agent}')
            return
        cells = [
            convert.point_to_cell(p.pose.position.x, p.pose.position.y, self.info)
            for p in msg.poses
        ]
        if None in cells or (msg.header.frame_id or self.frame_id) != self.frame_id:
            self.report('goal_path', DiagnosticStatus.WARN, 'goal_path ignored: off the map')
            return
        if cells[0] == self.path_goal:  # the path of the goal_pose just taken
            self.next_goals = cells[1:]

    def path_values(self, cell: tuple[int, int]) -> np.ndarray:
        """
        Minus the cost to reach `cell`.

        1 per move, 1.5 into an obstacle (puddle), so the walk takes a shortest path and goes round
        puddles when that is no longer. (The task's discounted values would rather stay out of a
        puddle forever than cross it.)
        """
        cost = np.where(self.obstacles[self.env.example], -1.5, -1.0)
        terminal = np.zeros(cost.shape, bool)
        cost[cell], terminal[cell] = 0.0, True
        return world.value_iteration(cost, terminal, gamma=1.0)

    def walk_step(self) -> None:
        if self.path_policy is None or self.env.done:
            return
        if self.env.agent == self.path_goal:
            self.path_policy = None
            if self.next_goals:  # a sequence's next step
                self.walk_to(self.next_goals.pop(0))
            return
        self.move(int(self.path_policy[self.env.agent]))

    def report(self, part: str, level: bytes, message: str, **values) -> None:
        report(self, self.diagnostics_pub, part, level, message, **values)


def main(args: list[str] | None = None) -> NoReturn:
    return spin(GridWorldNode, 'gridworld', args)


if __name__ == '__main__':
    sys.exit(main())
