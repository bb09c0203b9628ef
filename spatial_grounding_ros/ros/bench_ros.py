# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
End-to-end ROS latency for `spatial-grounding bench`.

The grounder node runs as its own process (as deployed); a client node in this process holds one
entity map on the topic and times each instruction from publish() to the goal_pose callback.
`python -m spatial_grounding_ros.ros.bench_ros` is the echo node that stands in for the grounder
to time rclpy and DDS alone: a goal_pose for each instruction, nothing done in between.
"""

from __future__ import annotations

import os
import random
import subprocess
import sys
import time

from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import OccupancyGrid
import numpy as np
import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from std_msgs.msg import Header, String

from . import convert
from .processes import executable, stop_processes
from .qos import LATCHED
from ..core import topics
from ..studies.measure import percentiles, rss_mb

# a namespace of this process's own (like the demo's): two benches, or a bench and a test
# run, that share a ROS_DOMAIN_ID never answer each other's requests
NAMESPACE = f'/bench_{os.getpid()}'


class EchoNode(Node):
    """Answer each instruction with an empty goal_pose: the round trip without a grounding."""

    def __init__(self):
        super().__init__('bench_echo')
        self.goal_pub = self.create_publisher(PoseStamped, topics.GOAL_POSE, 10)
        self.create_subscription(String, topics.INSTRUCTION, self.on_instruction, 10)

    def on_instruction(self, msg: String) -> None:
        self.goal_pub.publish(PoseStamped())


def echo_main() -> None:
    rclpy.init(args=sys.argv)
    node = EchoNode()
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


class LatencyClient(Node):
    """
    Publish instructions and time each to its goal_pose.

    It spins its executor in the thread that publishes, as a planner's own loop would, so no
    hand-over between a spinner thread and a waiting one (the client's cost, not the node's)
    is in the times.
    """

    def __init__(self, context):
        super().__init__('bench_client', namespace=NAMESPACE, context=context)
        self.map_pub = self.create_publisher(OccupancyGrid, topics.ENTITY_MAP, LATCHED)
        self.instruction_pub = self.create_publisher(String, topics.INSTRUCTION, 10)
        self.received_at = None
        self.create_subscription(PoseStamped, topics.GOAL_POSE, self.on_goal, 10)
        self.spinner = SingleThreadedExecutor(context=context)
        self.spinner.add_node(self)

    def on_goal(self, msg: PoseStamped) -> None:
        self.received_at = time.perf_counter()

    def connected(self) -> bool:
        return (
            self.instruction_pub.get_subscription_count() > 0
            and self.count_publishers(f'{NAMESPACE}/{topics.GOAL_POSE}') > 0
        )

    def spin_for(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.spinner.spin_once(timeout_sec=max(0.0, end - time.monotonic()))

    def request(self, text: str, timeout: float) -> float:
        """Seconds from publishing `text` to its goal_pose."""
        self.received_at = None
        sent = time.perf_counter()
        self.instruction_pub.publish(String(data=text))
        deadline = time.monotonic() + timeout
        while self.received_at is None:
            if time.monotonic() > deadline:
                raise RuntimeError(f'no goal_pose within {timeout} s for {text!r}')
            self.spinner.spin_once(timeout_sec=0.1)
        return self.received_at - sent


def round_trip_latency(
    checkpoint: str,
    grid: np.ndarray,
    instructions: list[str],
    requests: int,
    warmup: int = 20,
    progress=None,
    parameters: tuple = (),
    echo: bool = False,
) -> dict:
    """
    Measure p50/p99 instruction -> goal_pose latency and the grounder's RSS.

    p50/p99 of instruction -> goal_pose over `requests` requests on one held map, and the
    grounder process's RSS after the warm-up and at the end. `parameters`: more of the node's
    parameters, as `name:=value`. `echo`: the echo node in place of the grounder.
    """
    # loopback only, and a domain of its own unless the caller chose one (both processes)
    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    os.environ.setdefault('ROS_DOMAIN_ID', str(random.randint(1, 100)))
    node_command = [
        *executable('grounder'),
        '--ros-args',
        '-r',
        f'__ns:={NAMESPACE}',
        '-p',
        f'checkpoint:={checkpoint}',
        '-p',
        'entity_table:=entities_puddleworld.yaml',  # PuddleWorld maps (the default: office)
        '-p',
        # every instruction is timed to its goal_pose: none may be declined as unsure (an
        # uncalibrated checkpoint's confidence means little)
        'min_confidence:=0.0',
        *(a for p in parameters for a in ('-p', p)),
    ]
    if echo:
        node_command = [sys.executable, '-m', __name__, '--ros-args', '-r', f'__ns:={NAMESPACE}']
    node_process = subprocess.Popen(
        node_command,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    context = rclpy.Context()
    rclpy.init(context=context)
    client = LatencyClient(context)
    try:
        deadline = time.monotonic() + 60
        while not client.connected():
            if node_process.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError('the grounder node did not come up')
            client.spin_for(0.05)
        client.map_pub.publish(convert.grid_to_occupancy_grid(grid, Header(frame_id='map')))
        client.request(instructions[0], timeout=30)  # the first one also waits for the map
        for i in range(warmup):
            client.request(instructions[i % len(instructions)], timeout=10)
        rss_after_warmup = rss_mb(node_process.pid)
        latencies = []
        for i in range(requests):
            latencies.append(client.request(instructions[i % len(instructions)], timeout=10))
            if progress is not None:
                progress.update(1)
        rss_end = rss_mb(node_process.pid)
    finally:
        client.spinner.shutdown()
        client.destroy_node()
        context.try_shutdown()
        stop_processes(node_process)
    timing = percentiles(latencies)
    return {
        'requests': timing.pop('n'),
        'map': f'{grid.shape[0]}x{grid.shape[1]}',
        **timing,
        'node_rss_mb_after_warmup': rss_after_warmup,
        'node_rss_mb_end': rss_end,
        'measured': 'instruction published by a client node in the bench process -> '
        'goal_pose received by it; '
        + ('the echo node' if echo else 'the grounder node (console script)')
        + f' in its own process, one held map, {len(instructions)} instructions in turn, '
        f'{warmup} warm-up requests first',
    }


if __name__ == '__main__':
    echo_main()
