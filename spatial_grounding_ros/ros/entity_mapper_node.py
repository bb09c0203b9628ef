# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The entity mapper node (`ros2 run spatial_grounding_ros entity_mapper`).

A SLAM map plus named landmarks in, an entity map for the grounder out.

It subscribes `map` (nav_msgs/OccupancyGrid, as map_server or slam_toolbox latch it) and
`landmarks` (visualization_msgs/MarkerArray: each marker's `text`, or its `ns` when the text is
empty, names a kind of the entity table, its position is the landmark's place and its
scale.x/scale.y its footprint), and may read a file of landmarks that do not move
(`landmarks_file`). It publishes `entity_map` (nav_msgs/OccupancyGrid of entity indices) at
`cell_size` metres with the SLAM map's frame and origin pose: an entity cell holding any
occupied SLAM cell is the obstacle kind, one mostly unknown the unknown kind, the rest the free
kind, and each landmark's kind covers the cells of its footprint. It republishes when the map
or the landmarks change. A landmark name the table lacks, a marker in another frame or off the
map gets a WARN diagnostic and is left out.
"""

from __future__ import annotations

import array
import sys
from typing import NoReturn

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from nav_msgs.msg import OccupancyGrid
import numpy as np
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import Header
from visualization_msgs.msg import Marker, MarkerArray

from . import convert
from .entity_cells import (  # noqa: F401 - the mapper's geometry, also read from here
    entity_cells,
    entity_info,
    footprint_cells,
    kind_of,
    Landmark,
    marker_landmark,
    PLACE_TYPES,
    read_landmarks_file,
)
from .node_support import (
    autostart,
    declare_parameters,
    destroy_entities,
    error_text,
    guard_change_state,
    guarded,
    Param,
    publish_status,
    report,
    SEE_OVERRIDES,
    spin,
)
from .package_files import find_config
from .qos import LATCHED
from ..core import topics
from ..core.entities import EntityTable
from ..language.lexicon import Lexicon

NODE_NAME = 'entity_mapper'
# input topics of this node only (relative, like every topic of the package)
MAP = 'map'
LANDMARKS = 'landmarks'
# a SLAM map cell is occupied at map_server's default occupied_thresh 0.65
OCCUPIED_THRESHOLD = 65

PARAMETERS = (
    Param(
        'entity_table',
        'entities_office.yaml',
        'entity table whose kinds the entity_map holds and the landmarks name: a file in '
        'config/ or a path (give the grounder the same one)',
        read_only=True,
        non_empty=True,
    ),
    Param('cell_size', 0.25, 'metres per entity_map cell', read_only=True, low=1e-3, high=1e3),
    Param(
        'occupied_threshold',
        OCCUPIED_THRESHOLD,
        'a SLAM map cell with this value or more is occupied (map_server: occupied_thresh 0.65)',
        read_only=True,
        low=1,
        high=100,
    ),
    Param('free_kind', 'floor', 'kind of the free cells', read_only=True, non_empty=True),
    Param(
        'obstacle_kind',
        'wall',
        'kind of the cells holding an occupied SLAM cell',
        read_only=True,
        non_empty=True,
    ),
    Param(
        'unknown_kind',
        'unknown',
        'kind of the cells whose SLAM cells are mostly unknown (-1)',
        read_only=True,
        non_empty=True,
    ),
    Param(
        'landmarks_file',
        '',
        'YAML file of landmarks that do not move (landmarks: [{name, x, y, size}], in the '
        "map's frame); empty: none",
        read_only=True,
    ),
    Param(
        'landmarks_durability',
        'volatile',
        'durability of the landmarks subscription: volatile matches every publisher, '
        'transient_local also gets what a latched publisher sent before the node started',
        read_only=True,
        choices=('volatile', 'transient_local'),
    ),
    Param(
        'max_cells',
        4096 * 4096,
        'a SLAM map, or the entity map it makes at cell_size, of more cells is refused with a '
        'WARN (memory grows with the cells)',
        read_only=True,
        low=1,
        high=2**31 - 1,
    ),
    Param(
        'max_landmark_size',
        100.0,
        'a marker whose scale.x or scale.y is larger (metres), negative or not finite is '
        'skipped with a WARN',
        read_only=True,
        low=0.0,
        high=1e6,
    ),
    Param(
        'autostart',
        True,
        'configure and activate at start-up (false: wait for a lifecycle manager on '
        '<node>/change_state)',
        read_only=True,
    ),
)


class EntityMapperNode(LifecycleNode):
    """SLAM map + named landmarks -> entity map, republished on every change; a managed node."""

    def __init__(self, **node_options):
        super().__init__(NODE_NAME, **{**SEE_OVERRIDES, **node_options})
        declare_parameters(self, PARAMETERS)
        guard_change_state(self, self.state_label)
        self.table: EntityTable | None = None
        self.configure_error = ''
        self.active = self.autostarting = False
        self.topics = []
        self.fixed: list[Landmark] = []
        self.markers: dict[tuple[str, int], Landmark] = {}
        self.map_msg: OccupancyGrid | None = None
        self.slam: np.ndarray | None = None
        # the last landmark problems, kept in the 1 Hz status: a WARN sent once at start-up (a
        # latched bad marker) is lost to a monitor that matched /diagnostics a moment later
        self.skipped_warning = self.left_out_warning = ''
        self.diagnostics_pub = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS, 100)
        publish_status(self, self.diagnostics_pub, self.status)
        autostart(self)

    def param(self, name: str):
        return self.get_parameter(name).value

    def state_label(self) -> str:
        return 'active' if self.active else 'inactive' if self.table else 'unconfigured'

    def status(self) -> tuple[bytes, str, dict]:
        values = {
            'state': self.state_label(),
            'map': 'none' if self.slam is None else '{}x{}'.format(*self.slam.shape[::-1]),
            'landmarks': len(self.fixed) + len(self.markers),
        }
        if self.table is None and self.configure_error:
            return DiagnosticStatus.WARN, f'configure failed: {self.configure_error}', values
        warnings = [w for w in (self.skipped_warning, self.left_out_warning) if w]
        if warnings:
            return DiagnosticStatus.WARN, f'{values["state"]}; ' + '; '.join(warnings), values
        return DiagnosticStatus.OK, values['state'], values

    # --- lifecycle transitions

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        try:
            self.load_table()
        except Exception as exc:  # noqa: BLE001 - rclpy would swallow it: say what failed
            self.table = None
            self.configure_error = error_text(exc, (ValueError, OSError))
            if not self.autostarting:
                self.get_logger().error(f'configure failed: {self.configure_error}')
            return TransitionCallbackReturn.FAILURE
        self.configure_error = ''
        self.entity_pub = self.create_lifecycle_publisher(
            OccupancyGrid, topics.ENTITY_MAP, LATCHED
        )
        durability = (
            DurabilityPolicy.TRANSIENT_LOCAL
            if self.param('landmarks_durability') == 'transient_local'
            else DurabilityPolicy.VOLATILE
        )
        landmarks_qos = QoSProfile(
            depth=100, reliability=ReliabilityPolicy.RELIABLE, durability=durability
        )
        self.topics = [
            self.entity_pub,
            self.create_subscription(OccupancyGrid, MAP, self.on_map, LATCHED),
            self.create_subscription(MarkerArray, LANDMARKS, self.on_landmarks, landmarks_qos),
        ]
        return super().on_configure(state)

    def load_table(self) -> None:
        table_path = find_config(self.param('entity_table'))
        table = EntityTable.from_yaml(table_path)
        if len(table) > 128:
            raise ValueError(f'{table_path}: more than 128 kinds do not fit an OccupancyGrid cell')
        self.table, self.lexicon = table, Lexicon(table)
        self.kinds = tuple(
            self.table_kind(k) for k in ('free_kind', 'obstacle_kind', 'unknown_kind')
        )
        for role, kind in zip(('obstacle_kind', 'unknown_kind'), self.kinds[1:]):
            if kind not in table.obstacles:
                self.get_logger().warning(
                    f'{role} {table.names[kind]!r} is not an obstacle of {table_path}: '
                    'the grounder may send a goal onto it'
                )
        self.fixed = (
            read_landmarks_file(self.param('landmarks_file'))
            if self.param('landmarks_file')
            else []
        )
        self.get_logger().info(
            f'entity table {table_path}, {self.param("cell_size"):g} m cells, '
            f'{len(self.fixed)} landmarks from a file; waiting for {MAP}'
        )

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.active = True
        result = super().on_activate(state)
        self.publish()  # the map and landmarks held while inactive
        return result

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.active = False  # maps and landmarks are still taken and held
        return super().on_deactivate(state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.release()
        return super().on_cleanup(state)

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.release()
        return super().on_shutdown(state)

    def on_error(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.release()
        return TransitionCallbackReturn.SUCCESS

    def release(self) -> None:
        self.active = False
        destroy_entities(self, self.topics)
        self.topics, self.table, self.fixed, self.markers = [], None, [], {}
        self.map_msg = self.slam = None
        self.skipped_warning = self.left_out_warning = ''

    def destroy_node(self) -> None:
        self.release()
        super().destroy_node()

    def table_kind(self, parameter: str) -> int:
        name = self.param(parameter)
        if name not in self.table.names:
            raise ValueError(
                f'parameter {parameter} {name!r} is not a kind of the {self.table.domain} table '
                f'({", ".join(self.table.names)})'
            )
        return self.table.index(name)

    # --- topics

    @guarded('map')
    def on_map(self, msg: OccupancyGrid) -> None:
        try:
            limit = self.param('max_cells')
            convert.check_map_info(msg.info, max_cells=limit)
            if len(msg.data) != msg.info.width * msg.info.height:
                raise ValueError(
                    f'map data has {len(msg.data)} values, but width x height = '
                    f'{msg.info.width}x{msg.info.height}'
                )
            info = entity_info(msg.info, self.param('cell_size'))
            if info.width * info.height > limit:
                raise ValueError(
                    f'its entity map at cell_size={self.param("cell_size"):g} m would have '
                    f'{info.width}x{info.height} cells, more than max_cells={limit}'
                )
        except ValueError as exc:
            self.report('map', DiagnosticStatus.WARN, f'map rejected: {exc}')
            return
        data = (
            np.frombuffer(msg.data, dtype=np.int8)
            if isinstance(msg.data, array.array)
            else np.asarray(msg.data, dtype=np.int8)
        )
        self.slam = data.reshape(msg.info.height, msg.info.width)
        self.map_msg = msg
        self.publish()

    @guarded('landmarks')
    def on_landmarks(self, msg: MarkerArray) -> None:
        skipped = []
        for marker in msg.markers:
            key = (marker.ns, marker.id)
            if marker.action == Marker.DELETEALL:
                self.markers.clear()
            elif marker.action == Marker.DELETE:
                self.markers.pop(key, None)
            elif marker.action == Marker.ADD and marker.type in PLACE_TYPES:
                try:
                    self.markers[key] = marker_landmark(marker, self.param('max_landmark_size'))
                except ValueError as exc:  # the rest of the array still counts
                    self.markers.pop(key, None)
                    skipped.append(str(exc))
        self.skipped_warning = (
            f'skipped {len(skipped)} bad markers: ' + '; '.join(skipped[:10]) if skipped else ''
        )
        if skipped:
            self.report(
                'landmarks', DiagnosticStatus.WARN, self.skipped_warning, skipped=len(skipped)
            )
        self.publish()

    def landmark_cells(self, grid: np.ndarray, info) -> list[str]:
        """Paint every landmark's kind over its footprint; return the problems, one per line."""
        frame = self.map_msg.header.frame_id
        problems = []
        for landmark in [*self.fixed, *self.markers.values()]:
            kind = kind_of(self.lexicon, landmark.name)
            if kind is None:
                problems.append(
                    f'landmark {landmark.name!r} is not a kind of the {self.table.domain} table'
                )
                continue
            if landmark.frame_id and frame and landmark.frame_id != frame:
                problems.append(
                    f'landmark {landmark.name!r} is in frame {landmark.frame_id!r}, not the '
                    f"map's {frame!r}"
                )
                continue
            cells = footprint_cells(landmark, info)
            if cells is None:
                problems.append(
                    f'landmark {landmark.name!r} at ({landmark.x:g}, {landmark.y:g}) is off '
                    'the map'
                )
                continue
            grid[cells] = kind
        return problems

    def publish(self) -> None:
        """Build the entity map from the held SLAM map and landmarks, and publish it."""
        if self.map_msg is None or not self.active:
            return
        info = entity_info(self.map_msg.info, self.param('cell_size'))
        grid = entity_cells(
            self.slam,
            self.map_msg.info.resolution,
            info,
            self.kinds,
            self.param('occupied_threshold'),
        )
        problems = self.landmark_cells(grid, info)
        # stamped now: each entity map (a new SLAM map or new landmarks) is told apart by its
        # stamp, as the grounder's OK diagnostic reports it; the frame is the SLAM map's
        header = Header(
            stamp=self.get_clock().now().to_msg(), frame_id=self.map_msg.header.frame_id
        )
        msg = OccupancyGrid(header=header, info=info)
        msg.data = array.array('b', grid.astype(np.int8).tobytes())
        self.entity_pub.publish(msg)
        landmarks = len(self.fixed) + len(self.markers)
        self.left_out_warning = (
            f'left out {len(problems)} of {landmarks} landmarks: ' + '; '.join(problems)
            if problems
            else ''
        )
        if problems:
            self.report('landmarks', DiagnosticStatus.WARN, self.left_out_warning)
        self.report(
            'entity_map',
            DiagnosticStatus.OK,
            f'published a {info.width}x{info.height} entity_map with {landmarks - len(problems)} '
            'landmarks',
            width=info.width,
            height=info.height,
            landmarks=landmarks - len(problems),
        )

    def report(self, part: str, level: bytes, message: str, **values) -> None:
        report(self, self.diagnostics_pub, part, level, message, **values)


def main(args: list[str] | None = None) -> NoReturn:
    return spin(EntityMapperNode, 'entity_mapper', args)


if __name__ == '__main__':
    sys.exit(main())
