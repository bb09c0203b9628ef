# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The closed-loop demo.

The gridworld and grounder nodes run as real processes in a namespace of their own; the grounder
answers each episode's instruction with a goal_pose, the gridworld walks its agent there cell by
cell. A recorder in a thread of its own records every topic to an MCAP bag (log_time at reception,
whatever this thread is doing); this thread watches the topics, prints one line per episode and a
summary (also computed back from the bag with eval-bag), and draws a PNG per episode (map,
predicted values, |Z1|, the path taken).

The gridworld publishes its first episode only once the grounder, the recorder and the
watcher all subscribe to `instruction`, so each hears it live: no episode is restarted.
"""

from __future__ import annotations

import os
from pathlib import Path
import shutil
import subprocess
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import OccupancyGrid
import numpy as np
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from std_msgs.msg import Bool, Float32, Float32MultiArray, String
from std_srvs.srv import Trigger

from . import convert
from .bag_recorder import RecordingThread
from .processes import executable, stop_processes
from .qos import LATCHED, STREAM
from ..core import topics
from ..core.entities import PUDDLEWORLD
from ..data.bags import evaluate_bag
from ..data.datasets import DEFAULT_DATA
from ..studies.plots import plot_grounding
from ..training.options import ranged

# inputs nobody publishes in the demo: the action, and the robot pose a grounder may read
# (the watcher waits until every recorded topic has a publisher)
UNPUBLISHED = {topics.ACTION, getattr(topics, 'ROBOT_POSE', topics.ACTION)}
RECORDED = {  # topic -> type: every topic the two nodes publish here
    # the nodes' diagnostics are remapped into the demo's namespace: recorded there
    topic.lstrip('/'): msgtype
    for topic, msgtype in topics.MSGTYPES.items()
    if topic not in UNPUBLISHED
}
# How long every followed subscription must have been matched before the watcher subscribes
# to the instruction. A subscription counts a publisher as matched when its own reader has
# matched the writer; the writer in the other process matches the reader a moment later, and
# a volatile goal_pose sent in between is lost (CI lost episode 0's once, when the grounder
# had become fast enough to answer in that moment).
MATCH_SETTLE_S = 1.0


class DemoWatcher(Node):
    """Follows one episode at a time: the goal the grounder sent, the agent's moves."""

    def __init__(self, namespace: str):
        super().__init__('demo_watcher', namespace=namespace)
        self.goals: list[PoseStamped] = []
        self.poses: list[PoseStamped] = []
        self.rewards: list[float] = []
        self.terminated_msgs = 0
        self.terminated = False
        self.map_msg: OccupancyGrid | None = None
        self.values: Float32MultiArray | None = None
        self.relation: OccupancyGrid | None = None
        self.true_goal: PoseStamped | None = None
        self.instruction = ''
        self.declined: str | None = None  # the grounder's reason, when it sent no goal
        self.create_subscription(PoseStamped, topics.GOAL_POSE, self.goals.append, 10)
        self.create_subscription(PoseStamped, topics.AGENT_POSE, self.poses.append, STREAM)
        self.create_subscription(
            Float32, topics.REWARD, lambda m: self.rewards.append(m.data), STREAM
        )
        self.create_subscription(Bool, topics.TERMINATED, self.on_terminated, STREAM)
        # the nodes' diagnostics, remapped into the namespace: a decline is a WARN there
        self.create_subscription(
            DiagnosticArray, topics.DIAGNOSTICS.lstrip('/'), self.on_diagnostics, 10
        )
        self.create_subscription(
            OccupancyGrid, topics.ENTITY_MAP, lambda m: setattr(self, 'map_msg', m), LATCHED
        )
        self.create_subscription(
            Float32MultiArray, topics.VALUE_MAP_RAW, lambda m: setattr(self, 'values', m), LATCHED
        )
        self.create_subscription(
            OccupancyGrid, topics.RELATION_MAP, lambda m: setattr(self, 'relation', m), LATCHED
        )
        self.following = False  # subscribed to the instruction: see follow_instructions()
        self.matched_since: float | None = None  # every followed topic matched since then
        self.create_subscription(
            PoseStamped, topics.TRUE_GOAL, lambda m: setattr(self, 'true_goal', m), LATCHED
        )
        self.next_client = self.create_client(Trigger, topics.NEXT_EPISODE)
        self.reset_client = self.create_client(Trigger, topics.RESET_EPISODE)

    def follow_instructions(self, others: Node) -> bool:
        """
        Subscribe to the instruction once every topic followed here and by `others` is matched.

        The gridworld starts the first episode when the instruction has its subscribers, this
        one last, and a goal or a pose sent before its subscription is matched is lost: the
        topics must have stayed matched for MATCH_SETTLE_S, so the writers have matched too.
        """
        if self.following:
            return True
        if not all(
            s.get_publisher_count() > 0 for s in [*self.subscriptions, *others.subscriptions]
        ):
            self.matched_since = None
            return False
        self.matched_since = self.matched_since or time.monotonic()
        if time.monotonic() - self.matched_since >= MATCH_SETTLE_S:
            self.create_subscription(
                String, topics.INSTRUCTION, lambda m: setattr(self, 'instruction', m.data), LATCHED
            )
            self.following = True
        return self.following

    def on_diagnostics(self, msg: DiagnosticArray) -> None:
        for status in msg.status:
            if status.name.endswith(': grounding') and status.level == DiagnosticStatus.WARN:
                values = {v.key: v.value for v in status.values}
                self.declined = values.get('reason', status.message)

    def on_terminated(self, msg: Bool) -> None:
        self.terminated_msgs += 1
        self.terminated = self.terminated or msg.data

    def seen(self) -> dict[str, int]:
        """Messages of the per-episode topics seen so far in this episode."""
        return {
            'goal_pose': len(self.goals),
            'agent_pose': len(self.poses),
            'reward': len(self.rewards),
            'terminated': self.terminated_msgs,
        }

    def moves_complete(self) -> bool:
        """
        Every move seen so far (a pose after the start) has its reward and terminated flag too.

        They come on other topics and may trail the pose.
        """
        moves = len(self.poses) - 1
        return moves >= 0 and len(self.rewards) >= moves and self.terminated_msgs >= moves

    def clear(self) -> None:
        self.declined = None
        self.goals.clear()
        self.poses.clear()
        self.rewards.clear()
        self.terminated_msgs = 0
        self.terminated = False
        self.values = self.relation = None

    def cell(self, pose: PoseStamped) -> tuple[int, int]:
        return convert.point_to_cell(pose.pose.position.x, pose.pose.position.y, self.map_msg.info)


def spin_until(executor, condition, timeout: float, what: str, processes=()) -> None:
    """
    Spin until `condition()`.

    TimeoutError after `timeout`, RuntimeError as soon as one of `processes` ({log path: Popen})
    has exited, with the last line of its log.
    """
    deadline = time.monotonic() + timeout
    while not condition():
        for log, process in dict(processes).items():
            if process.poll() is not None:
                last = (log.read_text().strip().splitlines() or ['(no output)'])[-1]
                raise RuntimeError(
                    f'demo: {log.stem} exited ({process.returncode}) while '
                    f'waiting for {what}: {last} (see {log})'
                )
        if time.monotonic() > deadline:
            raise TimeoutError(f'demo: no {what} within {timeout:g} s')
        executor.spin_once(timeout_sec=0.02)


def start_nodes(logs: dict, common: list[str], source: list[str], gridworld: list[str]) -> list:
    """Start the grounder and gridworld processes, each writing to its log in `logs`."""
    env = {
        **os.environ,
        'ROS_AUTOMATIC_DISCOVERY_RANGE': os.environ.get(
            'ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST'
        ),
    }
    return [
        subprocess.Popen(
            # the gridworld's maps are PuddleWorld's (the grounder's default table: office)
            executable('grounder') + common + ['-p', 'entity_table:=entities_puddleworld.yaml'],
            env=env,
            stdout=logs['grounder'],
            stderr=subprocess.STDOUT,
        ),
        subprocess.Popen(
            executable('gridworld') + common + source + gridworld,
            env=env,
            stdout=logs['gridworld'],
            stderr=subprocess.STDOUT,
        ),
    ]


def follow_episode(
    executor, watcher: DemoWatcher, running: dict, step_limit: int, step_period: float
) -> dict:
    """
    Wait for the grounder's goal and the agent's walk to it; return what the watcher saw.

    The episode has begun: its instruction is out (or about to be), and the watcher was cleared.
    """
    spin_until(
        executor,
        lambda: (
            (watcher.goals or watcher.declined)
            and watcher.values is not None
            and watcher.relation is not None
        ),
        60,
        'grounding',
        running,
    )
    truth = watcher.cell(watcher.true_goal)
    if not watcher.goals:  # declined: no goal, so the agent stays where it is
        path = [watcher.cell(p) for p in watcher.poses[:1]]
        return {
            'goal': None,
            'reason': watcher.declined,
            'truth': truth,
            'end': path[-1] if path else None,
            'reached': False,
            'md': None,
            'reward': 0.0,
            'path': path,
        }
    goal = watcher.cell(watcher.goals[0])

    def settled() -> bool:
        at = watcher.cell(watcher.poses[-1]) if watcher.poses else None
        return watcher.moves_complete() and (
            watcher.terminated or at == goal or len(watcher.rewards) >= step_limit
        )

    spin_until(executor, settled, step_limit * step_period + 30, 'agent arrival', running)
    path = [watcher.cell(p) for p in watcher.poses]
    return {
        'goal': goal,
        'truth': truth,
        'end': path[-1],
        'reached': watcher.terminated,
        'md': abs(goal[0] - truth[0]) + abs(goal[1] - truth[1]),
        'reward': float(sum(watcher.rewards)),
        'path': path,
    }


def draw_episode(out: Path, k: int, watcher: DemoWatcher, seen: dict) -> None:
    """Draw episode `k` to a PNG and print its line."""
    goal, truth, path = seen['goal'], seen['truth'], seen['path']
    instruction = watcher.instruction
    grid = convert.occupancy_grid_to_grid(watcher.map_msg, 10**6)
    values = convert.float32_multiarray_to_value_map(watcher.values)
    relation = convert.occupancy_grid_to_grid(watcher.relation, 10**6).astype(float)
    png = plot_grounding(
        out / f'episode_{k}.png',
        grid,
        PUDDLEWORLD,
        values,
        relation,
        instruction if goal is not None else f'{instruction} (declined: {seen["reason"]})',
        goal,
        truth,
        path_cells=path,
    )
    if goal is None:
        print(f'[{k}] {instruction!r}: declined ({seen["reason"]}), no goal sent, true {truth} '
              f'-> {png}', flush=True)
        return
    outcome = (
        'reached the true goal'
        if seen['reached']
        else 'stopped at its goal_pose, not the true goal'
        if path[-1] == goal
        else 'did not get to its goal_pose'
    )
    line = (
        f'[{k}] {instruction!r}: goal {goal}, true {truth}, '
        f'{outcome}, '
        f'Manhattan error {seen["md"]}, {len(path) - 1} moves, reward {seen["reward"]:g} -> {png}'
    )
    print(line, flush=True)


def summarise(lines: list[dict], bag_path: Path, recorded: dict) -> dict:
    """Print and return the demo's summary, with the metrics computed back from the bag."""
    answered = [line for line in lines if line['goal'] is not None]
    summary = {
        'episodes': len(lines),
        'reached': sum(line['reached'] for line in lines),
        'declined': len(lines) - len(answered),
        # over the episodes it answered, as eval-bag counts MD
        'md': float(np.mean([line['md'] for line in answered])) if answered else None,
        'reward': float(np.mean([line['reward'] for line in lines])) if lines else None,
        'bag': str(bag_path),
        'from_bag': evaluate_bag(bag_path).metrics(),
        'recorded': recorded,
        'per_episode': lines,
    }
    bag = summary['from_bag']
    print(
        f'summary: {summary["reached"]}/{summary["episodes"]} episodes reached the goal, '
        f'{summary["declined"]} declined, mean Manhattan error of the answered '
        f'{summary["md"] if summary["md"] is None else round(summary["md"], 2)}, '
        f'mean reward {summary["reward"]:.2f}; '
        f'eval-bag on {bag_path}: n {bag["n"]}, MD {bag["md"]:.2f}, HIT {bag["hit"]:.2f}'
        + (f', PQ {bag["pq"]:.3f}, MSE {bag["mse"]:.3f}' if 'pq' in bag else '')
    )
    return summary


def node_arguments(
    namespace, use_data, data_dir, episodes, seed, step_period, step_limit, use_sim_time
):
    """Return the --ros-args both nodes share, the gridworld's source and its own."""
    source = (
        ['-p', 'source:=pw-local', '-p', 'split:=test', '-p', f'data_dir:={data_dir}']
        if use_data
        else ['-p', 'source:=generator', '-p', f'episodes:={episodes}']
    )
    common = ['--ros-args', '-r', f'__ns:={namespace}', '-r', topics.DIAGNOSTICS_INTO_NAMESPACE]
    if use_sim_time:
        common += ['-p', 'use_sim_time:=true']
    # the first episode waits for the instruction's three subscribers: the grounder, the
    # recorder and the watcher
    gridworld = [
        '-p', f'seed:={seed}', '-p', 'order:=sequential', '-p', f'step_limit:={step_limit}',
        '-p', f'step_period:={step_period}', '-p', 'start_after_subscribers:=3',
    ]  # fmt: skip
    return common, source, gridworld


def run_demo(
    out: str | Path,
    episodes: int = 5,
    seed: int = 7,
    data_dir: str = DEFAULT_DATA,
    step_period: float = 0.05,
    step_limit: int = 40,
    use_sim_time: bool = False,
) -> dict:
    """
    Run `episodes` episodes of the closed loop into `out`; return the summary.

    `use_sim_time` starts both nodes with use_sim_time:=true and nothing on /clock, as under a
    simulator that has not started its clock: the gridworld paces itself on steady time, and
    the goals and poses are stamped 0.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    bag_path = out / 'demo_bag'
    if bag_path.exists():
        shutil.rmtree(bag_path)
    use_data = (Path(data_dir) / 'puddleworld' / 'local.p').is_file()
    namespace = f'/demo_{os.getpid()}'
    common, source, gridworld = node_arguments(
        namespace, use_data, data_dir, episodes, seed, step_period, step_limit, use_sim_time
    )
    rclpy.init()
    watcher = recording = None
    processes, logs = [], {}
    executor = SingleThreadedExecutor()
    lines = []
    recorded_total = {}  # topic -> messages the watcher saw, which the bag must hold too
    try:
        watcher = DemoWatcher(namespace)
        executor.add_node(watcher)
        recording = RecordingThread(bag_path, RECORDED, topics.LATCHED, namespace=namespace)
        logs = {name: open(out / f'{name}.log', 'w') for name in ('grounder', 'gridworld')}
        processes = start_nodes(logs, common, source, gridworld)
        running = {
            Path(logs[name].name): p for name, p in zip(('grounder', 'gridworld'), processes)
        }
        print(
            f'gridworld ({"PuddleWorld local test maps" if use_data else "generated worlds"})'
            f' and grounder running in namespace {namespace}; recording to {bag_path}',
            flush=True,
        )
        for k in range(episodes):
            if k > 0:
                watcher.clear()
                future = watcher.next_client.call_async(Trigger.Request())
                spin_until(executor, future.done, 60, 'next episode', running)
            else:
                # both processes start (torch loads: slow on a busy machine), and the gridworld
                # publishes its first episode once the three subscribers are there
                spin_until(
                    executor,
                    lambda: watcher.follow_instructions(recording.recorder)
                    and watcher.count_subscribers(f'{namespace}/{topics.INSTRUCTION}') >= 3,
                    600,
                    'grounder subscription',
                    running,
                )
            seen = follow_episode(executor, watcher, running, step_limit, step_period)
            for topic, n in watcher.seen().items():
                recorded_total[topic] = recorded_total.get(topic, 0) + n
            draw_episode(out, k, watcher, seen)
            lines.append({k: v for k, v in seen.items() if k != 'path'})
        # the recorder hears what the watcher heard; wait until the bag holds it all
        full = {t: f'{namespace}/{t}' for t in recorded_total}
        spin_until(
            executor,
            lambda: all(recording.counts.get(full[t], 0) >= n for t, n in recorded_total.items()),
            30,
            'recording of the last messages',
        )
    finally:
        recorded = {}
        if recording is not None:
            recording.stop()
            recorded = recording.counts
        if watcher is not None:
            executor.remove_node(watcher)
            watcher.destroy_node()
        rclpy.try_shutdown()
        stop_processes(*processes)
        for log in logs.values():
            log.close()
    return summarise(lines, bag_path, recorded)


def cmd_closed_loop_demo(args) -> int:
    run_demo(args.out, args.episodes, args.seed, args.data, use_sim_time=args.use_sim_time)
    return 0


def register_cli(sub) -> None:
    d = sub.add_parser(
        'demo', help='gridworld + grounder nodes in a closed loop, recorded to a bag'
    )
    d.add_argument('--episodes', type=ranged(int, low=1), default=5)
    d.add_argument('--seed', type=ranged(int, low=0), default=7)
    d.add_argument(
        '--data',
        default=DEFAULT_DATA,
        help='PuddleWorld local test maps are used when this folder holds them',
    )
    d.add_argument('--out', default='demo_out')
    d.add_argument(
        '--use-sim-time',
        action='store_true',
        help='start the nodes with use_sim_time:=true (no /clock is published)',
    )
    d.set_defaults(func=cmd_closed_loop_demo)
