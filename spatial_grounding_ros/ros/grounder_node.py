"""The grounder node (`ros2 run spatial_grounding_ros grounder`): a thin adapter over
spatial_grounding_ros.grounder.Grounder.

Holds the latest valid entity_map and instruction; grounds when an instruction arrives and a
map is held (or when a map arrives for an instruction that is still waiting), then publishes
goal_pose, value_map, value_map_raw, relation_map and an OK diagnostic; each accepted map gets an
OK diagnostic too (`<node>: entity_map`, with the map's stamp). Bad input gets a
warning, a WARN diagnostic on /diagnostics, no goal, and the node keeps running.
"""
from __future__ import annotations

import sys

import numpy as np
import torch
import yaml
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import OccupancyGrid
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import Float32MultiArray, Header, String

from ..checkpoints import resolve_checkpoint
from ..entities import EntityTable
from ..grounder import Grounder
from . import convert
from .node_support import report, spin
from .package_files import find_config

NODE_NAME = "spatial_grounder"
PARAMS_FILE = "grounder.yaml"
# Like /map: a late subscriber (RViz, this node) still gets the latest map.
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)


def default_parameters() -> dict:
    """The node's parameters and defaults: config/grounder.yaml is the single source."""
    path = find_config(PARAMS_FILE)
    return yaml.safe_load(path.read_text())[NODE_NAME]["ros__parameters"]


class GrounderNode(Node):

    def __init__(self, **node_options):
        super().__init__(NODE_NAME, **node_options)
        for name, value in default_parameters().items():
            self.declare_parameter(name, value)

        if self.param("torch_threads") > 0:
            torch.set_num_threads(self.param("torch_threads"))
        self.grounder = Grounder.from_checkpoint(self.param("checkpoint"))
        table_path = find_config(self.param("entity_table"))
        table = EntityTable.from_yaml(table_path)
        if table.names != self.grounder.entities.names:
            raise ValueError(f"entity table {table_path} ({table.domain}, {len(table)} kinds) is "
                             f"not the one checkpoint {self.param('checkpoint')} was trained on "
                             f"({self.grounder.entities.domain}, "
                             f"{len(self.grounder.entities)} kinds)")
        self.get_logger().info(f"model {self.grounder.loaded.name} from "
                               f"{resolve_checkpoint(self.param('checkpoint'))}, "
                               f"entity table {table_path}")

        self.grid: np.ndarray | None = None     # latest valid map, row 0 = north
        self.map_msg: OccupancyGrid | None = None
        self.instruction: str | None = None     # latest valid instruction
        self.instruction_pending = False        # not yet grounded on any map

        self.goal_pub = self.create_publisher(PoseStamped, self.param("goal_pose_topic"), 10)
        self.value_map_pub = self.create_publisher(OccupancyGrid, self.param("value_map_topic"),
                                                   LATCHED)
        self.value_raw_pub = self.create_publisher(Float32MultiArray,
                                                   self.param("value_map_raw_topic"), LATCHED)
        self.relation_map_pub = self.create_publisher(OccupancyGrid,
                                                      self.param("relation_map_topic"), LATCHED)
        self.diagnostics_pub = self.create_publisher(DiagnosticArray,
                                                     self.param("diagnostics_topic"), 10)
        self.create_subscription(OccupancyGrid, self.param("entity_map_topic"), self.on_entity_map,
                                 LATCHED)
        self.create_subscription(String, self.param("instruction_topic"), self.on_instruction, 10)

    def param(self, name: str):
        return self.get_parameter(name).value

    def on_entity_map(self, msg: OccupancyGrid) -> None:
        try:
            grid = convert.occupancy_grid_to_grid(msg, self.param("max_cells"))
            self.grounder.check_grid(grid)
        except ValueError as exc:
            # a stale map could send the robot somewhere that no longer fits: drop it
            self.grid = self.map_msg = None
            self.report("entity_map", DiagnosticStatus.WARN,
                        f"entity_map rejected: {exc}; no map held until a valid one arrives")
            return
        self.grid, self.map_msg = grid, msg
        # an OK per accepted map, naming its stamp: a client can tell that the node holds the
        # map it sent before it sends an instruction (topics are not ordered among each other)
        stamp = msg.header.stamp
        self.report("entity_map", DiagnosticStatus.OK,
                    f"holding a {grid.shape[0]}x{grid.shape[1]} entity_map (frame "
                    f"{msg.header.frame_id!r}, stamp {stamp.sec}.{stamp.nanosec:09d})",
                    stamp_sec=stamp.sec, stamp_nanosec=stamp.nanosec,
                    height=grid.shape[0], width=grid.shape[1])
        if self.instruction is not None and (
                self.instruction_pending or self.param("reground_on_map_change")):
            self.ground()

    def on_instruction(self, msg: String) -> None:
        text = msg.data
        limit = self.param("max_instruction_chars")
        try:
            if not text.strip():
                raise ValueError("instruction is empty")
            if len(text) > limit:
                raise ValueError(f"instruction has {len(text)} characters, more than "
                                 f"max_instruction_chars={limit}")
            self.grounder.check_instruction(text)
        except ValueError as exc:
            self.instruction, self.instruction_pending = None, False
            self.report("instruction", DiagnosticStatus.WARN, f"instruction rejected: {exc}")
            return
        self.instruction, self.instruction_pending = text, True
        if self.grid is None:
            self.report("instruction", DiagnosticStatus.WARN,
                        f"no valid entity_map held yet: holding instruction {text!r} until one "
                        "arrives")
            return
        self.ground()

    def ground(self) -> None:
        try:
            result = self.grounder.ground(self.grid, self.instruction)
        except Exception as exc:  # noqa: BLE001 - e.g. out of memory in torch: report, keep running
            self.report("grounding", DiagnosticStatus.ERROR,
                        f"grounding {self.instruction!r} failed: {type(exc).__name__}: {exc}")
            return
        self.instruction_pending = False
        info = self.map_msg.info
        header = Header(stamp=self.get_clock().now().to_msg(),
                        frame_id=self.map_msg.header.frame_id
                        or self.param("default_frame_id"))
        # goal first: it is what a planner waits for
        self.goal_pub.publish(convert.cell_to_pose(result.goal, info, header.frame_id,
                                                   header.stamp))
        self.value_map_pub.publish(convert.value_map_to_occupancy_grid(result.values, header,
                                                                       info))
        self.value_raw_pub.publish(convert.value_map_to_float32_multiarray(result.values))
        self.relation_map_pub.publish(convert.magnitude_to_occupancy_grid(result.relation_map,
                                                                          header, info))
        message = f"grounded {result.instruction!r} at cell (row, col) {result.goal}"
        if result.unknown_words:
            message += f"; ignored unknown words {result.unknown_words}"
        self.report("grounding", DiagnosticStatus.OK, message,
                    goal_row=result.goal[0], goal_col=result.goal[1])

    def report(self, part: str, level: bytes, message: str, **values) -> None:
        report(self, self.diagnostics_pub, part, level, message, **values)


def main(args: list[str] | None = None) -> int:
    return spin(GrounderNode, "grounder", args)


if __name__ == "__main__":
    sys.exit(main())
