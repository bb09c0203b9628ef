# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The grounder node (`ros2 run spatial_grounding_ros grounder`).

A lifecycle node over spatial_grounding_ros.grounder.Grounder, as Nav2's servers: configure
loads the checkpoint and the entity table and creates the topics and the ground_instruction
service; activate starts grounding; deactivate stops it (and drops the held instruction);
cleanup releases all. `autostart` (the default) configures and activates at start-up.

While active it holds the latest valid entity_map and instruction and grounds when both are
there (an instruction waits for a map at most instruction_timeout), publishing goal_pose (none
on a decline), value_map, value_map_raw, value_map_image, relation_map and a diagnostic (OK,
or WARN naming the decline's reason); the node's state is on /diagnostics every second. Bad
input gets a warning, a WARN diagnostic, no goal, and the node keeps running. The service
ground_instruction (ground_service.py) answers one instruction without publishing. Topic names
are fixed and relative: remap them (`-r goal_pose:=...`).
"""

from __future__ import annotations

import sys
import time
from typing import NoReturn

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import OccupancyGrid
import numpy as np
from rclpy.clock import Clock, ClockType
from rclpy.lifecycle import (
    LifecycleNode,
    LifecyclePublisher,
    LifecycleState,
    TransitionCallbackReturn,
)
from rclpy.publisher import Publisher
from rclpy.service import Service
from sensor_msgs.msg import Image
from spatial_grounding_interfaces.srv import GroundInstruction
from std_msgs.msg import Float32MultiArray, Header, String
import torch

from . import convert
from .ground_service import answer, goal_pose
from .grounder_parameters import PARAMETERS
from .node_support import (
    declare_parameters,
    guard_change_state,
    publish_status,
    report,
    SEE_OVERRIDES,
    spin,
)
from .package_files import find_config
from .qos import LATCHED
from ..core import topics
from ..core.entities import EntityTable
from ..grounder import Grounder, Grounding
from ..models.checkpoints import load_checkpoint, resolve_checkpoint

NODE_NAME = 'spatial_grounder'
STEADY = ClockType.STEADY_TIME  # instruction_timeout is wall time, also under use_sim_time


class GrounderNode(LifecycleNode):
    """Entity map + instruction -> goal_pose and value maps, as a managed node."""

    def __init__(self, **node_options):
        super().__init__(NODE_NAME, **{**SEE_OVERRIDES, **node_options})
        declare_parameters(self, PARAMETERS)
        guard_change_state(self, self.state_label)
        self.grounder: Grounder | None = None
        self.configure_error = ''
        self.active = self.autostarting = False
        self.topics = []  # publishers, subscriptions and the service of configure
        self.expiry_timer = None
        self.robot_yaw: float | None = None  # of the latest robot_pose (goal_heading: keep)
        self.release_input()
        # diagnostics in every state: they say why an instruction was not grounded
        self.diagnostics_pub = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS, 10)
        publish_status(self, self.diagnostics_pub, self.status)
        if not self.param('autostart'):
            self.get_logger().info(
                f'unconfigured: waiting for a lifecycle manager on '
                f'{self.get_fully_qualified_name()}/change_state'
            )
            return
        self.autostarting = True  # a failed configure is then main()'s one error line
        try:
            if self.trigger_configure() != TransitionCallbackReturn.SUCCESS:
                raise ValueError(self.configure_error)
            self.trigger_activate()
        finally:
            self.autostarting = False

    def param(self, name: str):
        return self.get_parameter(name).value

    def state_label(self) -> str:
        return 'active' if self.active else 'inactive' if self.grounder else 'unconfigured'

    def status(self) -> tuple[bytes, str, dict]:
        """Return the 1 Hz status: the lifecycle state, the map held, an instruction waiting."""
        values = {
            'state': self.state_label(),
            'map': 'none' if self.grid is None else '{}x{}'.format(*self.grid.shape),
            'instruction_waiting': self.instruction if self.instruction_pending else '',
        }
        if self.grounder is None and self.configure_error:
            return DiagnosticStatus.WARN, f'configure failed: {self.configure_error}', values
        return DiagnosticStatus.OK, values['state'], values

    def release_input(self) -> None:
        self.grid: np.ndarray | None = None  # latest valid map, row 0 = north
        self.map_msg: OccupancyGrid | None = None
        self.drop_instruction()

    def drop_instruction(self) -> None:
        self.instruction: str | None = None  # latest valid instruction
        self.instruction_pending = False  # not yet grounded on any map
        self.instruction_received = 0.0  # time.monotonic() of its arrival
        if self.expiry_timer is not None:
            self.destroy_timer(self.expiry_timer)
            self.expiry_timer = None

    # --- lifecycle transitions

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        try:
            self.load_model()
        except Exception as exc:  # noqa: BLE001 - rclpy would swallow it: say what failed
            self.configure_error = (
                str(exc)
                if isinstance(exc, (ValueError, OSError))
                else f'{type(exc).__name__}: {exc}'
            )
            if not self.autostarting:
                self.get_logger().error(f'configure failed: {self.configure_error}')
            return TransitionCallbackReturn.FAILURE
        self.configure_error = ''
        publisher = self.create_lifecycle_publisher
        self.goal_pub = publisher(PoseStamped, topics.GOAL_POSE, 10)
        self.value_map_pub = publisher(OccupancyGrid, topics.VALUE_MAP, LATCHED)
        self.value_raw_pub = publisher(Float32MultiArray, topics.VALUE_MAP_RAW, LATCHED)
        self.value_image_pub = publisher(Image, topics.VALUE_MAP_IMAGE, LATCHED)
        self.relation_map_pub = publisher(OccupancyGrid, topics.RELATION_MAP, LATCHED)
        subscription = self.create_subscription
        self.topics = [
            self.goal_pub,
            self.value_map_pub,
            self.value_raw_pub,
            self.value_image_pub,
            self.relation_map_pub,
            subscription(OccupancyGrid, topics.ENTITY_MAP, self.on_entity_map, LATCHED),
            subscription(String, topics.INSTRUCTION, self.on_instruction, 10),
            subscription(PoseStamped, topics.ROBOT_POSE, self.on_robot_pose, 10),
            # ground_service.answer: one grounding per request, nothing published
            self.create_service(
                GroundInstruction,
                topics.GROUND_INSTRUCTION,
                lambda request, response: answer(self, request, response),
            ),
        ]
        return super().on_configure(state)

    def load_model(self) -> None:
        if self.param('torch_threads') > 0:
            torch.set_num_threads(self.param('torch_threads'))
        table_path = find_config(self.param('entity_table'))
        table = EntityTable.from_yaml(table_path)
        # a PuddleWorld model reads any table; another only its own (Grounder says so)
        grounder = Grounder(
            load_checkpoint(self.param('checkpoint')),
            table,
            self.param('min_confidence'),
            mirror_average_cells=self.param('mirror_average_cells'),
        )
        self.grounder = grounder
        self.get_logger().info(
            f'model {grounder.loaded.name} from '
            f'{resolve_checkpoint(self.param("checkpoint"))}, '
            f'entity table {table_path}'
        )

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.active = True
        self.get_logger().info('active: grounding instructions')
        return super().on_activate(state)

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        # a goal from an instruction given before the pause would surprise: drop it
        self.active = False
        self.drop_instruction()
        self.get_logger().info('inactive: instructions are not grounded')
        return super().on_deactivate(state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.release()
        return super().on_cleanup(state)

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.release()
        return super().on_shutdown(state)

    def on_error(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.release()
        return TransitionCallbackReturn.SUCCESS  # back to unconfigured

    def release(self) -> None:
        """Give back what configure took: the model, the held input, the topics, the service."""
        self.active = False
        for entity in self.topics:
            if isinstance(entity, LifecyclePublisher):
                self.destroy_lifecycle_publisher(entity)
            elif isinstance(entity, Publisher):
                self.destroy_publisher(entity)
            elif isinstance(entity, Service):
                self.destroy_service(entity)
            else:
                self.destroy_subscription(entity)
        self.topics = []
        self.grounder = None
        self.robot_yaw = None
        self.release_input()

    def destroy_node(self) -> None:
        self.release()  # as a shutdown transition would: model and topics first
        super().destroy_node()

    # --- topics

    def on_entity_map(self, msg: OccupancyGrid) -> None:
        try:
            grid = convert.occupancy_grid_to_grid(msg, self.param('max_cells'))
            self.grounder.check_grid(grid)
        except ValueError as exc:
            # a stale map could send the robot somewhere that no longer fits: drop it
            self.grid = self.map_msg = None
            self.report(
                'entity_map',
                DiagnosticStatus.WARN,
                f'entity_map rejected: {exc}; no map held until a valid one arrives',
            )
            return
        self.grid, self.map_msg = grid, msg
        # an OK per accepted map, naming its stamp: a client can tell that the node holds the
        # map it sent before it sends an instruction (topics are not ordered among each other)
        stamp = msg.header.stamp
        self.report(
            'entity_map',
            DiagnosticStatus.OK,
            f'holding a {grid.shape[0]}x{grid.shape[1]} entity_map (frame '
            f'{msg.header.frame_id!r}, stamp {stamp.sec}.{stamp.nanosec:09d})',
            stamp_sec=stamp.sec,
            stamp_nanosec=stamp.nanosec,
            height=grid.shape[0],
            width=grid.shape[1],
        )
        if self.instruction_pending and self.instruction_expired():
            self.expire_instruction()  # the timer's tick may not have come yet
        if (
            self.active
            and self.instruction is not None
            and (self.instruction_pending or self.param('reground_on_map_change'))
        ):
            self.ground()

    def check_text(self, text: str) -> None:
        """Raise ValueError naming what is wrong with an instruction (or the node's state)."""
        if not self.active:
            raise ValueError(
                'the node is inactive (activate it through '
                f'{self.get_fully_qualified_name()}/change_state)'
            )
        if not text.strip():
            raise ValueError('instruction is empty')
        limit = self.param('max_instruction_chars')
        if len(text) > limit:
            raise ValueError(
                f'instruction has {len(text)} characters, more than '
                f'max_instruction_chars={limit}'
            )
        self.grounder.check_instruction(text)

    def on_instruction(self, msg: String) -> None:
        text = msg.data
        try:
            self.check_text(text)
        except ValueError as exc:
            self.drop_instruction()
            self.report('instruction', DiagnosticStatus.WARN, f'instruction rejected: {exc}')
            return
        self.drop_instruction()
        self.instruction, self.instruction_pending = text, True
        self.instruction_received = time.monotonic()
        if self.grid is None:
            timeout = self.param('instruction_timeout')
            if timeout > 0:
                self.expiry_timer = self.create_timer(
                    timeout, self.expire_instruction, clock=Clock(clock_type=STEADY)
                )
            self.report(
                'instruction',
                DiagnosticStatus.WARN,
                f'no valid entity_map held yet: holding instruction {text!r} until one arrives'
                + (f' (for at most {timeout:g} s)' if timeout > 0 else ''),
            )
            return
        self.ground()

    def instruction_expired(self) -> bool:
        timeout = self.param('instruction_timeout')
        return timeout > 0 and time.monotonic() - self.instruction_received >= timeout

    def expire_instruction(self) -> None:
        """Drop an instruction that waited instruction_timeout for a map, saying so."""
        text, pending = self.instruction, self.instruction_pending
        self.drop_instruction()
        if pending:
            self.report(
                'instruction',
                DiagnosticStatus.WARN,
                f'instruction {text!r} expired: no valid entity_map within '
                f'instruction_timeout={self.param("instruction_timeout"):g} s; dropped, '
                'send it again',
            )

    def on_robot_pose(self, msg: PoseStamped) -> None:
        yaw = convert.quaternion_yaw(msg.pose.orientation)
        if np.isfinite(yaw):
            self.robot_yaw = yaw

    def run_grounder(self, grid: np.ndarray, text: str, map_msg: OccupancyGrid) -> Grounding:
        self.grounder.min_confidence = self.param('min_confidence')  # settable at run time
        return self.grounder.ground(grid, text, cell_size=map_msg.info.resolution)

    def output_header(self, map_msg: OccupancyGrid) -> Header:
        # the map's stamp: the maps are that map's cells, placed where the map was then
        return Header(
            stamp=map_msg.header.stamp,
            frame_id=map_msg.header.frame_id or self.param('default_frame_id'),
        )

    def ground(self) -> None:
        try:
            result = self.run_grounder(self.grid, self.instruction, self.map_msg)
        except Exception as exc:  # noqa: BLE001 - e.g. out of memory in torch: report, go on
            self.report(
                'grounding',
                DiagnosticStatus.ERROR,
                f'grounding {self.instruction!r} failed: {type(exc).__name__}: {exc}',
            )
            return
        self.instruction_pending = False
        if self.expiry_timer is not None:
            self.destroy_timer(self.expiry_timer)
            self.expiry_timer = None
        info = self.map_msg.info
        header = self.output_header(self.map_msg)
        # goal first: it is what a planner waits for; a declined grounding sends none
        if result.goal is not None:
            self.goal_pub.publish(goal_pose(self, result.goal, result, info, header))
        self.value_map_pub.publish(
            convert.value_map_to_occupancy_grid(
                result.values, header, info, self.param('value_map_encoding')
            )
        )
        self.value_raw_pub.publish(convert.value_map_to_float32_multiarray(result.values))
        self.value_image_pub.publish(convert.value_map_to_image(result.values, header))
        self.relation_map_pub.publish(
            convert.magnitude_to_occupancy_grid(result.relation_map, header, info)
        )
        if result.goal is None:
            self.report(
                'grounding',
                DiagnosticStatus.WARN,
                f'declined {result.instruction!r}: {result.reason}; no goal sent',
                reason=result.reason,
                confidence=f'{result.confidence:.3f}',
            )
            return
        message = f'grounded {result.instruction!r} at cell (row, col) {result.goal}'
        if result.unknown_words:
            message += f'; ignored unknown words {result.unknown_words}'
        self.report(
            'grounding',
            DiagnosticStatus.OK,
            message,
            goal_row=result.goal[0],
            goal_col=result.goal[1],
            confidence=f'{result.confidence:.3f}',
        )

    def report(self, part: str, level: bytes, message: str, **values) -> None:
        report(self, self.diagnostics_pub, part, level, message, **values)


def main(args: list[str] | None = None) -> NoReturn:
    return spin(GrounderNode, 'grounder', args)


if __name__ == '__main__':
    sys.exit(main())
