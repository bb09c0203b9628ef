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
from dataclasses import dataclass
import math
from pathlib import Path
import sys
from typing import NoReturn

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from nav_msgs.msg import MapMetaData, OccupancyGrid
import numpy as np
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import Header
from visualization_msgs.msg import Marker, MarkerArray
import yaml

from . import convert
from .node_support import declare_parameters, Param, report, spin
from .package_files import find_config
from .qos import LATCHED
from ..core import topics
from ..core.entities import EntityTable
from ..core.map_geometry import origin_quaternion, rotate
from ..language.lexicon import Lexicon, phrase_words, singular

NODE_NAME = 'entity_mapper'
# input topics of this node only (relative, like every topic of the package)
MAP = 'map'
LANDMARKS = 'landmarks'
# marker types that place a landmark; the rest (arrows, lines, meshes) are not places
PLACE_TYPES = (Marker.CUBE, Marker.CYLINDER, Marker.TEXT_VIEW_FACING)
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
)


@dataclass(frozen=True)
class Landmark:
    """A named place: its map-frame centre and footprint (0: one cell)."""

    name: str
    x: float
    y: float
    size_x: float = 0.0
    size_y: float = 0.0
    frame_id: str = ''  # empty: the map's frame


def entity_info(info: MapMetaData, cell_size: float) -> MapMetaData:
    """Return the entity map's meta data: the SLAM map's origin pose, `cell_size` cells over it."""
    out = MapMetaData()
    out.resolution = float(cell_size)
    # a message's resolution is a float32 (0.05 is 0.0500000007): tolerate its rounding
    out.width = max(1, math.ceil(info.width * info.resolution / cell_size - 1e-4))
    out.height = max(1, math.ceil(info.height * info.resolution / cell_size - 1e-4))
    out.origin = info.origin
    return out


def entity_cells(
    slam: np.ndarray, resolution: float, info: MapMetaData, kinds: tuple[int, int, int], thr: int
) -> np.ndarray:
    """
    Return the (height, width) kinds of the entity map, in OccupancyGrid order (row 0 at origin).

    `slam` is the SLAM map in the same order. Each SLAM cell belongs to the entity cell holding
    its centre; an entity cell with an occupied SLAM cell is `kinds` obstacle, one with more
    unknown than known cells unknown, else free. An entity cell smaller than a SLAM cell reads
    the SLAM cell under its own centre. `kinds` is (free, obstacle, unknown).
    """
    free, obstacle, unknown = kinds
    h, w = info.height, info.width
    ratio = resolution / info.resolution
    rows = np.minimum(((np.arange(slam.shape[0]) + 0.5) * ratio).astype(np.int64), h - 1)
    cols = np.minimum(((np.arange(slam.shape[1]) + 0.5) * ratio).astype(np.int64), w - 1)
    owner = (rows[:, None] * w + cols[None, :]).ravel()
    cells = slam.ravel()
    total = np.bincount(owner, minlength=h * w)
    occupied = np.bincount(owner, weights=cells >= thr, minlength=h * w) > 0
    unknowns = np.bincount(owner, weights=cells < 0, minlength=h * w)
    out = np.where(occupied, obstacle, np.where(2 * unknowns > total, unknown, free))
    empty = np.flatnonzero(total == 0)
    if empty.size:  # cells finer than the SLAM map: the SLAM cell under the centre
        r = np.minimum(((empty // w + 0.5) / ratio).astype(np.int64), slam.shape[0] - 1)
        c = np.minimum(((empty % w + 0.5) / ratio).astype(np.int64), slam.shape[1] - 1)
        under = slam[r, c]
        out[empty] = np.where(under >= thr, obstacle, np.where(under < 0, unknown, free))
    return out.reshape(h, w)


def footprint_cells(landmark: Landmark, info: MapMetaData) -> tuple[slice, slice] | None:
    """
    Return the (rows, cols) slices, OccupancyGrid order, of the cells a landmark covers.

    The cells whose centres lie in its footprint (axis-aligned with the grid), or the one cell
    under its centre when the footprint holds no cell centre; None when that is off the map.
    """
    p = info.origin.position
    inverse = origin_quaternion(info.origin) * np.array([-1, -1, -1, 1])
    lx, ly, _ = rotate(inverse, np.array([landmark.x - p.x, landmark.y - p.y, 0.0]))
    size = info.resolution
    spans = []
    axes = ((ly, landmark.size_y, info.height), (lx, landmark.size_x, info.width))
    for centre, extent, n in axes:
        first = math.ceil((centre - extent / 2) / size - 0.5 - 1e-9)
        last = math.floor((centre + extent / 2) / size - 0.5 + 1e-9)
        if extent <= 0 or last < first:
            first = last = math.floor(centre / size)
        first, last = max(first, 0), min(last, n - 1)
        if last < first:
            return None
        spans.append(slice(first, last + 1))
    return spans[0], spans[1]


def kind_of(lexicon: Lexicon, name: str) -> int | None:
    """Return the kind a landmark name (a name, alias, plural or one-edit typo) names, or None."""
    words = phrase_words(name)
    if not words:
        return None
    if len(words) == 1:
        return lexicon.word_kind(words[0])
    return lexicon.phrase_kind(words[:-1] + (singular(words[-1]),))


def read_landmarks_file(path: str | Path) -> list[Landmark]:
    """
    Read `landmarks: [{name, x, y, size}]` (size: metres, a number or [x, y]; omitted: one cell).

    An optional top-level `frame_id` applies to every landmark. ValueError says what is wrong.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f'{path}: landmarks file not found')
    data = yaml.safe_load(path.read_text()) or {}
    items = data.get('landmarks') if isinstance(data, dict) else None
    if not isinstance(items, list):
        raise ValueError(f'{path}: a landmarks file holds `landmarks:`, a list of {{name, x, y}}')
    frame = str(data.get('frame_id') or '')
    out = []
    for i, item in enumerate(items):
        try:
            size = item.get('size', 0.0)
            sx, sy = (size, size) if isinstance(size, (int, float)) else size
            landmark = Landmark(
                str(item['name']), float(item['x']), float(item['y']), float(sx), float(sy), frame
            )
        except (AttributeError, KeyError, TypeError, ValueError) as exc:
            raise ValueError(
                f'{path}: landmark {i} ({item!r}) needs name, x, y and may give size '
                f'(a number or [x, y]): {exc}'
            ) from exc
        if not all(map(math.isfinite, (landmark.x, landmark.y, landmark.size_x, landmark.size_y))):
            raise ValueError(f'{path}: landmark {i} ({item!r}) has a non-finite number')
        out.append(landmark)
    return out


class EntityMapperNode(Node):
    """SLAM map + named landmarks -> entity map, republished on every change."""

    def __init__(self, **node_options):
        super().__init__(NODE_NAME, **node_options)
        declare_parameters(self, PARAMETERS)
        table_path = find_config(self.param('entity_table'))
        self.table = EntityTable.from_yaml(table_path)
        if len(self.table) > 128:
            raise ValueError(f'{table_path}: more than 128 kinds do not fit an OccupancyGrid cell')
        self.lexicon = Lexicon(self.table)
        self.kinds = tuple(
            self.table_kind(k) for k in ('free_kind', 'obstacle_kind', 'unknown_kind')
        )
        for role, kind in zip(('obstacle_kind', 'unknown_kind'), self.kinds[1:]):
            if kind not in self.table.obstacles:
                self.get_logger().warning(
                    f'{role} {self.table.names[kind]!r} is not an obstacle of {table_path}: '
                    'the grounder may send a goal onto it'
                )
        self.fixed = (
            read_landmarks_file(self.param('landmarks_file'))
            if self.param('landmarks_file')
            else []
        )
        self.markers: dict[tuple[str, int], Landmark] = {}
        self.map_msg: OccupancyGrid | None = None
        self.slam: np.ndarray | None = None
        self.entity_pub = self.create_publisher(OccupancyGrid, topics.ENTITY_MAP, LATCHED)
        self.diagnostics_pub = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS, 10)
        self.create_subscription(OccupancyGrid, MAP, self.on_map, LATCHED)
        durability = (
            DurabilityPolicy.TRANSIENT_LOCAL
            if self.param('landmarks_durability') == 'transient_local'
            else DurabilityPolicy.VOLATILE
        )
        landmarks_qos = QoSProfile(
            depth=10, reliability=ReliabilityPolicy.RELIABLE, durability=durability
        )
        self.create_subscription(MarkerArray, LANDMARKS, self.on_landmarks, landmarks_qos)
        self.get_logger().info(
            f'entity table {table_path}, {self.param("cell_size"):g} m cells, '
            f'{len(self.fixed)} landmarks from a file; waiting for {MAP}'
        )

    def param(self, name: str):
        return self.get_parameter(name).value

    def table_kind(self, parameter: str) -> int:
        name = self.param(parameter)
        if name not in self.table.names:
            raise ValueError(
                f'parameter {parameter} {name!r} is not a kind of the {self.table.domain} table '
                f'({", ".join(self.table.names)})'
            )
        return self.table.index(name)

    def on_map(self, msg: OccupancyGrid) -> None:
        try:
            convert.check_map_info(msg.info, max_cells=2**31)
            if len(msg.data) != msg.info.width * msg.info.height:
                raise ValueError(
                    f'map data has {len(msg.data)} values, but width x height = '
                    f'{msg.info.width}x{msg.info.height}'
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

    def on_landmarks(self, msg: MarkerArray) -> None:
        for marker in msg.markers:
            key = (marker.ns, marker.id)
            if marker.action == Marker.DELETEALL:
                self.markers.clear()
            elif marker.action == Marker.DELETE:
                self.markers.pop(key, None)
            elif marker.action == Marker.ADD and marker.type in PLACE_TYPES:
                p = marker.pose.position
                self.markers[key] = Landmark(
                    marker.text.strip() or marker.ns,
                    p.x,
                    p.y,
                    max(marker.scale.x, 0.0),
                    max(marker.scale.y, 0.0),
                    marker.header.frame_id,
                )
        self.publish()

    def landmark_cells(self, grid: np.ndarray, info: MapMetaData) -> list[str]:
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
        if self.map_msg is None:
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
        if problems:
            self.report(
                'landmarks',
                DiagnosticStatus.WARN,
                f'left out {len(problems)} of {landmarks} landmarks: ' + '; '.join(problems),
            )
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
