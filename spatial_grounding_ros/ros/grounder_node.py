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

While active it holds the latest valid entity_map and instruction (core/instruction_hold.py has
the rules) and grounds when both are there, publishing goal_pose (none on a decline, a stop or a
question), goal_path (a sequence's goals; empty for a stop), the latched value_map(_raw, _image)
and relation_map (each built once someone subscribes: LatchedOutput) and a diagnostic naming the
intent; its state is on /diagnostics every second. Bad input gets a warning, a WARN diagnostic,
no goal, and the node keeps serving. The service ground_instruction answers one instruction
without publishing, or refuses it at once as `busy` when max_pending_requests are in flight.

Threads: inputs, status, lifecycle and topic groundings on maps of up to INLINE_CELLS cells run
in the spinning thread (spin()'s ServingExecutor); larger maps' on a thread the inputs wake;
service requests on max_pending_requests + 1 threads: a long grounding neither stops the status
nor the inputs. One grounding runs at a time (the model lock, taken again by its holder).
"""

from __future__ import annotations

import sys
import threading
from typing import NoReturn

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import OccupancyGrid, Path
import numpy as np
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.clock import Clock, ClockType
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from sensor_msgs.msg import Image
from spatial_grounding_interfaces.srv import GroundInstruction
from std_msgs.msg import Float32MultiArray, Header, String
import torch

from . import convert
from .executors import Worker
from .ground_service import grounding_report, intent, Poser, refuse, response
from .grounder_parameters import PARAMETERS
from .latched_output import LatchedOutput
from .node_support import (
    autostart,
    declare_parameters,
    destroy_entities,
    error_text,
    guard_change_state,
    guarded,
    publish_status,
    report,
    SEE_OVERRIDES,
    spin,
)
from .package_files import find_config
from .qos import BURST, LATCHED
from ..core import topics
from ..core.entities import EntityTable
from ..core.instruction_hold import Dropped, goal_stamp, InstructionHold
from ..core.map_geometry import point_to_cell
from ..grounder import Grounder, Grounding
from ..models.checkpoints import load_checkpoint, resolve_checkpoint

NODE_NAME = 'spatial_grounder'
STEADY = ClockType.STEADY_TIME  # instruction_timeout is wall time, also under use_sim_time
# maps of at most this many cells ground in the spinning thread (in 17 ms or less with the
# mirror images, make bench): a hand-over to the grounding thread and back cost a small map's
# goal about 1 ms at p50; larger ones ground on that thread, so the inputs are taken meanwhile
INLINE_CELLS = 64 * 64


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
        # the latest robot_pose's (x, y): an approach goal is the side the robot reaches first
        self.robot_xy: tuple[float, float] | None = None
        self.model_lock = threading.RLock()  # one grounding at a time: torch, the text cache
        self.state_lock = threading.RLock()  # the hold and the map, shared by the callbacks
        self.requests = 0  # ground_instruction requests in flight
        self.grounding = ''  # the instruction a topic grounding works on
        self.hold = InstructionHold()
        self.service_group = ReentrantCallbackGroup()
        # a large map's topic groundings run on a thread of their own (ground_soon), so the
        # inputs are taken meanwhile
        self.topic_grounding = Worker(self.ground_held, 'topic groundings')
        self.release_input()
        # diagnostics in every state: they say why an instruction was not grounded; deep
        # enough for a burst's reports
        self.diagnostics_pub = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS, 100)
        publish_status(self, self.diagnostics_pub, self.status)
        autostart(self)

    def param(self, name: str):
        return self.get_parameter(name).value

    def pooled_groups(self) -> tuple:
        """Return the callback groups spin() runs on its request threads: the service's."""
        return (self.service_group,)

    def request_threads(self) -> int:
        """Every request in flight may wait for the model, and one more is refused at once."""
        return self.param('max_pending_requests') + 1

    def state_label(self) -> str:
        return 'active' if self.active else 'inactive' if self.grounder else 'unconfigured'

    def status(self) -> tuple[bytes, str, dict]:
        """Return the 1 Hz status: the state, the map held, the instructions and requests."""
        values = {
            'state': self.state_label(),
            'map': 'none' if self.grid is None else '{}x{}'.format(*self.grid.shape),
            'instruction_waiting': self.hold.text if self.hold.pending else '',
            'grounding': self.grounding,
            'requests_in_flight': self.requests,
        }
        if self.grounder is None and self.configure_error:
            return DiagnosticStatus.WARN, f'configure failed: {self.configure_error}', values
        return DiagnosticStatus.OK, values['state'], values

    def release_input(self) -> None:
        with self.state_lock:
            self.grid: np.ndarray | None = None  # latest valid map, row 0 = north
            self.map_msg: OccupancyGrid | None = None
            self.drop_instruction('inactive')

    def drop_instruction(self, why: str) -> Dropped | None:
        with self.state_lock:
            self.cancel_expiry()
            return self.hold.drop(why)

    def cancel_expiry(self) -> None:
        with self.state_lock:
            if self.expiry_timer is not None:
                self.destroy_timer(self.expiry_timer)
                self.expiry_timer = None

    # --- lifecycle transitions

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        try:
            self.load_model()
        except Exception as exc:  # noqa: BLE001 - rclpy would swallow it: say what failed
            self.configure_error = error_text(exc, (ValueError, OSError))
            if not self.autostarting:
                self.get_logger().error(f'configure failed: {self.configure_error}')
            return TransitionCallbackReturn.FAILURE
        self.configure_error = ''
        publisher = self.create_lifecycle_publisher
        self.goal_pub = publisher(PoseStamped, topics.GOAL_POSE, 10)
        self.path_pub = publisher(Path, topics.GOAL_PATH, 10)
        latched = ((OccupancyGrid, topics.VALUE_MAP), (Float32MultiArray, topics.VALUE_MAP_RAW),
                   (Image, topics.VALUE_MAP_IMAGE), (OccupancyGrid, topics.RELATION_MAP))
        self.latched = {topic: LatchedOutput(self, kind, topic) for kind, topic in latched}
        subscription = self.create_subscription
        self.topics = [
            self.goal_pub,
            self.path_pub,
            *(output.publisher for output in self.latched.values()),
            subscription(OccupancyGrid, topics.ENTITY_MAP, self.on_entity_map, LATCHED),
            subscription(String, topics.INSTRUCTION, self.on_instruction, BURST),
            subscription(PoseStamped, topics.ROBOT_POSE, self.on_robot_pose, 10),
            self.create_service(
                GroundInstruction,
                topics.GROUND_INSTRUCTION,
                self.on_ground_request,
                qos_profile=BURST,
                callback_group=self.service_group,
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
            mirror_average_below=self.param('mirror_average_below'),
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
        with self.state_lock:
            self.active = False
            self.drop_instruction('inactive')
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
        with self.model_lock:  # a grounding under way ends first
            destroy_entities(self, self.topics)
            self.topics = []
            self.grounder = None
            self.robot_yaw = self.robot_xy = None
            self.release_input()

    def destroy_node(self) -> None:
        self.topic_grounding.stop()  # a grounding under way ends first
        self.release()  # as a shutdown transition would: model and topics first
        super().destroy_node()

    # --- topics (in the spinning thread; groundings run in ground_held, see ground_soon)

    @guarded('entity_map')
    def on_entity_map(self, msg: OccupancyGrid) -> None:
        try:
            grid = convert.occupancy_grid_to_grid(msg, self.param('max_cells'))
            self.grounder.check_grid(grid)
        except ValueError as exc:
            # a stale map could send the robot somewhere that no longer fits: drop it
            with self.state_lock:
                self.grid = self.map_msg = None
            self.report(
                'entity_map',
                DiagnosticStatus.WARN,
                f'entity_map rejected: {exc}; no map held until a valid one arrives',
            )
            return
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
        with self.state_lock:
            self.grid, self.map_msg = grid, msg
            self.report_dropped(self.hold.expire(self.param('instruction_timeout')))
            reground = self.active and self.hold.on_map(self.param('reground_on_map_change'))
        if reground:
            self.ground_soon()

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

    @guarded('instruction')
    def on_instruction(self, msg: String) -> None:
        text = msg.data
        try:
            self.check_text(text)
        except ValueError as exc:
            dropped = self.drop_instruction('rejected')
            also = f'; dropped the waiting instruction {dropped.text!r}' if dropped else ''
            self.report('instruction', DiagnosticStatus.WARN, f'instruction rejected: {exc}{also}')
            return
        with self.state_lock:
            self.cancel_expiry()
            self.report_dropped(self.hold.hold(text))
            held_map = self.grid is not None
            timeout = self.param('instruction_timeout')
            if not held_map and timeout > 0:
                self.expiry_timer = self.create_timer(
                    timeout,
                    self.expire_instruction,
                    clock=Clock(clock_type=STEADY),
                )
        if held_map:
            self.ground_soon()
            return
        self.report(
            'instruction',
            DiagnosticStatus.WARN,
            f'no valid entity_map held yet: holding instruction {text!r} until one arrives'
            + (f' (for at most {timeout:g} s)' if timeout > 0 else ''),
        )

    @guarded('instruction')
    def expire_instruction(self) -> None:
        """Drop an instruction that waited instruction_timeout for a map, saying so."""
        with self.state_lock:
            self.report_dropped(self.drop_instruction('expired'))

    def report_dropped(self, dropped: Dropped | None) -> None:
        """Say that an instruction was let go of without a grounding (expired, superseded)."""
        if dropped is not None:
            message = dropped.message(self.param('instruction_timeout'))
            self.report('instruction', DiagnosticStatus.WARN, message, dropped=dropped.text)

    @guarded('robot_pose')
    def on_robot_pose(self, msg: PoseStamped) -> None:
        yaw = convert.quaternion_yaw(msg.pose.orientation)
        if np.isfinite(yaw):
            self.robot_yaw = yaw
        x, y = msg.pose.position.x, msg.pose.position.y
        if np.isfinite(x) and np.isfinite(y):
            self.robot_xy = (x, y)

    # --- grounding

    def run_grounder(self, grid: np.ndarray, text: str, map_msg: OccupancyGrid) -> Grounding:
        """Ground one instruction; one at a time (the model lock). ValueError if unconfigured."""
        with self.model_lock:
            if self.grounder is None:
                raise ValueError('the node is not configured')
            self.grounder.min_confidence = self.param('min_confidence')  # settable at run time
            robot = None if self.robot_xy is None else point_to_cell(*self.robot_xy, map_msg.info)
            return self.grounder.ground(
                grid, text, cell_size=map_msg.info.resolution, robot_cell=robot
            )

    def poser(self, map_msg: OccupancyGrid) -> Poser:
        # the map's stamp (goal_stamp: map): the goal is that map's cell, where the map was then
        stamp = goal_stamp(
            self.param('goal_stamp'),
            map_msg.header.stamp,
            lambda: self.get_clock().now().to_msg(),
        )
        frame = map_msg.header.frame_id or self.param('default_frame_id')
        header = Header(stamp=stamp, frame_id=frame)
        return Poser(map_msg.info, header, self.param('goal_heading'), self.robot_yaw)

    def ground_soon(self) -> None:
        """Ground the held instruction: a small map's here, if the model is free (taken first)."""
        small = self.grid is not None and self.grid.size <= INLINE_CELLS
        if not (small and self.topic_grounding.idle() and self.model_lock.acquire(blocking=False)):
            self.topic_grounding.wake()  # it takes the held instruction once it is free
            return
        try:  # taken before: no service request takes the model between the check and this
            self.ground_held()
        finally:
            self.model_lock.release()

    @guarded('grounding')
    def ground_held(self) -> None:
        """Ground the held instruction on the held map, if it still waits (see ground_soon)."""
        with self.state_lock:
            text = self.hold.take() if self.active and self.grid is not None else None
            if text is None:
                return
            grid, map_msg = self.grid, self.map_msg
            self.cancel_expiry()
        self.grounding = text
        try:
            result = self.run_grounder(grid, text, map_msg)
        except Exception as exc:  # noqa: BLE001 - e.g. out of memory in torch: report, go on
            self.report(
                'grounding',
                DiagnosticStatus.ERROR,
                f'grounding {text!r} failed: {type(exc).__name__}: {exc}',
            )
            return
        finally:
            self.grounding = ''
        if self.active:  # not deactivated meanwhile
            self.publish(result, map_msg)

    def publish(self, result: Grounding, map_msg: OccupancyGrid) -> None:
        info, poser = map_msg.info, self.poser(map_msg)
        header = Header(stamp=map_msg.header.stamp, frame_id=poser.header.frame_id)
        # goal first: it is what a planner waits for; a declined grounding sends none
        goal = poser.goal(result) if result.reason is None else None
        if goal is not None:
            self.goal_pub.publish(goal)
        # a volatile topic with no subscriber would drop the message: it is not built
        path_wanted = self.path_pub.get_subscription_count() > 0
        if path_wanted and (goal is not None or intent(result) == 'stop'):
            self.path_pub.publish(poser.path(result))  # a stop's is empty
        self.offer_maps(result.values, result.relation_map, header, info)
        level, message, values = grounding_report(result)
        self.report('grounding', level, message, **values)

    def offer_maps(self, values, relation, header: Header, info) -> None:
        """Offer the latched value maps and relation map, each built once someone subscribes."""
        out, encoding = self.latched, self.param('value_map_encoding')
        if values is not None and np.size(values):
            out[topics.VALUE_MAP].offer(
                lambda: convert.value_map_to_occupancy_grid(values, header, info, encoding)
            )
            raw, image = convert.value_map_to_float32_multiarray, convert.value_map_to_image
            out[topics.VALUE_MAP_RAW].offer(lambda: raw(values))
            out[topics.VALUE_MAP_IMAGE].offer(lambda: image(values, header))
        if relation is not None and np.size(relation):
            out[topics.RELATION_MAP].offer(
                lambda: convert.magnitude_to_occupancy_grid(relation, header, info)
            )

    def on_ground_request(self, request, reply):
        """Answer GroundInstruction at once when max_pending_requests are in flight: busy."""
        with self.state_lock:
            limit = self.param('max_pending_requests')
            if self.requests >= limit:
                return refuse(
                    reply,
                    f'busy: {self.requests} requests in flight (max_pending_requests={limit}); '
                    'try again',
                )
            self.requests += 1
        try:
            return self.answer(request, reply)
        finally:
            with self.state_lock:
                self.requests -= 1

    def answer(self, request, reply):
        """One grounding, nothing published, nothing held; a refusal says why, never raises."""
        try:
            self.check_text(request.instruction)
            map_msg = request.entity_map
            if len(map_msg.data) == 0:
                with self.state_lock:
                    grid, map_msg = self.grid, self.map_msg
                if grid is None:
                    raise ValueError(
                        'the request has no entity_map (empty data) and no valid entity_map '
                        'is held'
                    )
            else:
                grid = convert.occupancy_grid_to_grid(map_msg, self.param('max_cells'))
                self.grounder.check_grid(grid)
            result = self.run_grounder(grid, request.instruction, map_msg)
            return response(reply, result, self.poser(map_msg))
        except Exception as exc:  # noqa: BLE001 - an answer, never a crash of the node
            reason = error_text(exc, (ValueError,))
            self.get_logger().debug(f'ground_instruction refused: {reason}')
            return refuse(reply, reason)

    def report(self, part: str, level: bytes, message: str, **values) -> None:
        report(self, self.diagnostics_pub, part, level, message, **values)


def main(args: list[str] | None = None) -> NoReturn:
    return spin(GrounderNode, 'grounder', args)


if __name__ == '__main__':
    sys.exit(main())
