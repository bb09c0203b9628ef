# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The grounder node (`ros2 run spatial_grounding_ros grounder`).

A lifecycle node over spatial_grounding_ros.grounder.Grounder.

Lifecycle (as Nav2's servers): configure loads and checks the checkpoint and the entity
table and creates the topics; activate starts grounding; deactivate stops it (no goal is
published while inactive, and the held instruction is dropped); cleanup releases the model,
the map and the topics. With `autostart` (the default) the node configures and activates
itself, so `ros2 run` alone works; with `autostart: false` it waits, unconfigured, for a
lifecycle manager on `<node>/change_state`.

While active it holds the latest valid entity_map and instruction; it grounds when an
instruction arrives and a map is held (or when a map arrives for an instruction that is still
waiting), then publishes goal_pose, value_map, value_map_raw, relation_map and an OK
diagnostic; each accepted map gets an OK diagnostic too (`<node>: entity_map`, with the map's
stamp). Bad input gets a warning, a WARN diagnostic on /diagnostics, no goal, and the node
keeps running. Topic names are fixed and relative: remap them (`-r goal_pose:=...`).
"""

from __future__ import annotations

import sys
from typing import NoReturn

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import OccupancyGrid
import numpy as np
from rclpy.lifecycle import (
    LifecycleNode,
    LifecyclePublisher,
    LifecycleState,
    TransitionCallbackReturn,
)
from rclpy.publisher import Publisher
from std_msgs.msg import Float32MultiArray, Header, String
import torch

from . import convert
from .node_support import declare_parameters, Param, report, spin
from .package_files import find_config
from .qos import LATCHED
from ..core import topics
from ..core.entities import EntityTable
from ..grounder import DEFAULT_CHECKPOINT, Grounder
from ..models.checkpoints import load_checkpoint, resolve_checkpoint

NODE_NAME = 'spatial_grounder'

PARAMETERS = (
    Param(
        'checkpoint',
        DEFAULT_CHECKPOINT,
        'packaged checkpoint name (spatial_grounding_ros/checkpoints/<name>.pt) or a path '
        'to a .pt; loaded on configure',
        read_only=True,
        non_empty=True,
    ),
    Param(
        'entity_table',
        'entities_puddleworld.yaml',
        'entity table naming the entity_map cell values: a file in config/ or a path; it '
        'must be the table the checkpoint was trained on (checked on configure)',
        read_only=True,
        non_empty=True,
    ),
    Param(
        'max_cells',
        1024 * 1024,
        'larger entity maps are rejected (work and memory grow with the cells: a 1024x1024 '
        'map grounds in about a second, peak RSS under 1 GB; docs/benchmarks.md)',
        low=1,
        high=4096 * 4096,
    ),
    Param('max_instruction_chars', 500, 'longer instructions are rejected', low=1, high=100000),
    Param(
        'reground_on_map_change',
        False,
        'ground the held instruction again on each new entity_map (false: a new map is used '
        'by the next instruction, so Nav2 does not get a new goal on every map update)',
    ),
    Param(
        'value_map_encoding',
        'display',
        'value_map cells: display = best cell 100, worst 0 (a colour ramp); cost = best 0, '
        'worst 100, as a costmap reads cells (100 = lethal)',
        choices=convert.VALUE_MAP_ENCODINGS,
    ),
    Param(
        'default_frame_id',
        'map',
        "frame of the outputs when the entity_map's header.frame_id is empty",
        non_empty=True,
    ),
    Param(
        'torch_threads',
        1,
        'torch intra-op threads (process-wide), set on configure: 1 keeps latency steady '
        "next to other busy processes, 0 leaves torch's default (all cores)",
        read_only=True,
        low=0,
        high=1024,
    ),
    Param(
        'autostart',
        True,
        'configure and activate at start-up (false: wait for a lifecycle manager on '
        '<node>/change_state)',
        read_only=True,
    ),
)


class GrounderNode(LifecycleNode):
    """Entity map + instruction -> goal_pose and value maps, as a managed node."""

    def __init__(self, **node_options):
        super().__init__(NODE_NAME, **node_options)
        declare_parameters(self, PARAMETERS)
        self.guard_change_state()
        self.grounder: Grounder | None = None
        self.configure_error = ''
        self.active = self.autostarting = False
        self.topics = []  # publishers and subscriptions of configure
        self.release_input()
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

    def guard_change_state(self) -> None:
        """
        Answer a change_state request for a transition the current state does not have.

        Answer a change_state request for a transition the current state does not have
        (activate while unconfigured, ...) with success false, as rclcpp does: rclpy raises
        in the service callback, which would end the node's spin.
        """
        service = getattr(self, '_service_change_state', None)
        if service is None:  # made with enable_communication_interface=False
            return
        change_state = service.callback

        def guarded(request, response):
            try:
                return change_state(request, response)
            except RuntimeError as exc:  # rclpy's RCLError: the transition is not registered
                self.get_logger().warning(
                    f'transition {request.transition.id} {request.transition.label!r} refused '
                    f'in state {self._state_machine.current_state[1]!r}: '
                    f'{str(exc).split(",")[0]}'
                )
                response.success = False
                return response

        service.callback = guarded

    def release_input(self) -> None:
        self.grid: np.ndarray | None = None  # latest valid map, row 0 = north
        self.map_msg: OccupancyGrid | None = None
        self.instruction: str | None = None  # latest valid instruction
        self.instruction_pending = False  # not yet grounded on any map

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
        self.goal_pub = self.create_lifecycle_publisher(PoseStamped, topics.GOAL_POSE, 10)
        self.value_map_pub = self.create_lifecycle_publisher(
            OccupancyGrid, topics.VALUE_MAP, LATCHED
        )
        self.value_raw_pub = self.create_lifecycle_publisher(
            Float32MultiArray, topics.VALUE_MAP_RAW, LATCHED
        )
        self.relation_map_pub = self.create_lifecycle_publisher(
            OccupancyGrid, topics.RELATION_MAP, LATCHED
        )
        # diagnostics also while inactive: they say why an instruction was not grounded
        self.diagnostics_pub = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS, 10)
        self.topics = [
            self.goal_pub,
            self.value_map_pub,
            self.value_raw_pub,
            self.relation_map_pub,
            self.diagnostics_pub,
            self.create_subscription(
                OccupancyGrid, topics.ENTITY_MAP, self.on_entity_map, LATCHED
            ),
            self.create_subscription(String, topics.INSTRUCTION, self.on_instruction, 10),
        ]
        return super().on_configure(state)

    def load_model(self) -> None:
        if self.param('torch_threads') > 0:
            torch.set_num_threads(self.param('torch_threads'))
        table_path = find_config(self.param('entity_table'))
        table = EntityTable.from_yaml(table_path)
        grounder = Grounder(load_checkpoint(self.param('checkpoint'), expect_entities=table))
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
        self.instruction, self.instruction_pending = None, False
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
        """Give back what configure took: the model, the held input, the topics."""
        self.active = False
        for entity in self.topics:
            if isinstance(entity, LifecyclePublisher):
                self.destroy_lifecycle_publisher(entity)
            elif isinstance(entity, Publisher):
                self.destroy_publisher(entity)
            else:
                self.destroy_subscription(entity)
        self.topics = []
        self.grounder = None
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
        if (
            self.active
            and self.instruction is not None
            and (self.instruction_pending or self.param('reground_on_map_change'))
        ):
            self.ground()

    def on_instruction(self, msg: String) -> None:
        text = msg.data
        limit = self.param('max_instruction_chars')
        try:
            if not self.active:
                raise ValueError(
                    'the node is inactive (activate it through '
                    f'{self.get_fully_qualified_name()}/change_state)'
                )
            if not text.strip():
                raise ValueError('instruction is empty')
            if len(text) > limit:
                raise ValueError(
                    f'instruction has {len(text)} characters, more than '
                    f'max_instruction_chars={limit}'
                )
            self.grounder.check_instruction(text)
        except ValueError as exc:
            self.instruction, self.instruction_pending = None, False
            self.report('instruction', DiagnosticStatus.WARN, f'instruction rejected: {exc}')
            return
        self.instruction, self.instruction_pending = text, True
        if self.grid is None:
            self.report(
                'instruction',
                DiagnosticStatus.WARN,
                f'no valid entity_map held yet: holding instruction {text!r} until one arrives',
            )
            return
        self.ground()

    def ground(self) -> None:
        try:
            result = self.grounder.ground(self.grid, self.instruction)
        except Exception as exc:  # noqa: BLE001 - e.g. out of memory in torch: report, go on
            self.report(
                'grounding',
                DiagnosticStatus.ERROR,
                f'grounding {self.instruction!r} failed: {type(exc).__name__}: {exc}',
            )
            return
        self.instruction_pending = False
        info = self.map_msg.info
        # the map's stamp: the goal is a cell of that map, placed where the map was then
        # (a map in odom moves with the robot; tf2 reads stamp 0 as "latest")
        header = Header(
            stamp=self.map_msg.header.stamp,
            frame_id=self.map_msg.header.frame_id or self.param('default_frame_id'),
        )
        # goal first: it is what a planner waits for; a declined grounding sends none
        if result.goal is not None:
            self.goal_pub.publish(
                convert.cell_to_pose(result.goal, info, header.frame_id, header.stamp)
            )
        self.value_map_pub.publish(
            convert.value_map_to_occupancy_grid(
                result.values, header, info, self.param('value_map_encoding')
            )
        )
        self.value_raw_pub.publish(convert.value_map_to_float32_multiarray(result.values))
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
