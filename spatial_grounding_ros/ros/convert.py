# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Conversions between grids / value maps and ROS messages. Pure functions, no node.

Orientation (DESIGN "ROS interface"): a data-set grid's row 0 is the north (top) row, while
an OccupancyGrid's row index grows with +y (row 0 sits at the map origin). So data-set row r
is OccupancyGrid row height-1-r, and "northernmost" means largest y in the map frame.
Cell centres go through the full origin pose (position and rotation) and the resolution.
"""

from __future__ import annotations

import array
import math

from builtin_interfaces.msg import Time
from geometry_msgs.msg import Pose, PoseStamped
from nav_msgs.msg import MapMetaData, OccupancyGrid
import numpy as np
from std_msgs.msg import Float32MultiArray, Header, MultiArrayDimension

from ..bags import multiarray_to_map

PERCENT = 100  # OccupancyGrid cell values for RViz: 0..100
# value_map cells: best = 100 (display) or best = 0 (cost, as a costmap reads it)
VALUE_MAP_ENCODINGS = ('display', 'cost')


def _quaternion(pose: Pose) -> np.ndarray:
    """(x, y, z, w) of a pose's orientation, normalised; ValueError if it is not a rotation."""
    o = pose.orientation
    q = np.array([o.x, o.y, o.z, o.w], dtype=np.float64)
    norm = float(np.linalg.norm(q))
    if not np.isfinite(q).all() or norm < 1e-9:
        raise ValueError(f'map origin orientation {q.tolist()} is not a valid quaternion')
    return q / norm


def _rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate 3-vector(s) v (..., 3) by the unit quaternion q = (x, y, z, w)."""
    u, w = q[:3], q[3]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def check_map_info(info: MapMetaData, max_cells: int) -> None:
    """Raise ValueError naming what is wrong with a map's size, resolution or origin."""
    if info.width == 0 or info.height == 0:
        raise ValueError(
            f'map size is {info.width}x{info.height} (width x height): '
            'width and height must be positive'
        )
    cells = info.width * info.height
    if cells > max_cells:
        raise ValueError(
            f'map has {cells} cells ({info.width}x{info.height}), more than max_cells={max_cells}'
        )
    if not math.isfinite(info.resolution) or info.resolution <= 0:
        raise ValueError(f'map resolution {info.resolution} must be a positive finite number')
    p = info.origin.position
    if not all(math.isfinite(c) for c in (p.x, p.y, p.z)):
        raise ValueError(f'map origin position ({p.x}, {p.y}, {p.z}) is not finite')
    _quaternion(info.origin)


def occupancy_grid_to_grid(msg: OccupancyGrid, max_cells: int) -> np.ndarray:
    """
    Convert an entity map message to a (H, W) int64 grid, row 0 = north.

    ValueError on bad input.

    Entity values are not checked here: that needs the entity table (Grounder.check_grid).
    """
    info = msg.info
    check_map_info(info, max_cells)
    if len(msg.data) != info.width * info.height:
        raise ValueError(
            f'map data has {len(msg.data)} values, but width x height = '
            f'{info.width}x{info.height} = {info.width * info.height}'
        )
    cells = (
        np.frombuffer(msg.data, dtype=np.int8)
        if isinstance(msg.data, array.array)
        else np.asarray(msg.data, dtype=np.int8)
    )
    return cells.astype(np.int64).reshape(info.height, info.width)[::-1].copy()


def map_info(
    shape: tuple[int, int],
    resolution: float = 1.0,
    origin: tuple[float, float] = (0.0, 0.0),
    yaw: float = 0.0,
) -> MapMetaData:
    """
    Meta data of a (H, W) grid.

    `origin` is the (x, y) of the south-west corner, `yaw` the rotation of the grid's x axis (east)
    in the map frame.
    """
    info = MapMetaData()
    info.height, info.width = int(shape[0]), int(shape[1])
    info.resolution = float(resolution)
    info.origin.position.x, info.origin.position.y = float(origin[0]), float(origin[1])
    info.origin.orientation.z = math.sin(yaw / 2.0)
    info.origin.orientation.w = math.cos(yaw / 2.0)
    return info


def grid_to_occupancy_grid(
    grid: np.ndarray, header: Header, info: MapMetaData | None = None
) -> OccupancyGrid:
    """
    Convert a (H, W) grid of entity indices (row 0 = north) to an entity map message.

    `info` defaults to map_info(grid.shape) (1 m cells, origin at 0, 0).
    """
    grid = np.asarray(grid)
    if grid.min(initial=0) < -128 or grid.max(initial=0) > 127:
        raise ValueError('entity indices must fit an OccupancyGrid cell (int8)')
    msg = OccupancyGrid(header=header, info=info if info is not None else map_info(grid.shape))
    msg.data = array.array('b', grid[::-1].astype(np.int8).tobytes())
    return msg


def _scaled_grid(percent: np.ndarray, header: Header, info: MapMetaData) -> OccupancyGrid:
    msg = OccupancyGrid(header=header, info=info)
    msg.data = array.array('b', np.rint(percent)[::-1].astype(np.int8).tobytes())
    return msg


def value_map_to_occupancy_grid(
    values: np.ndarray, header: Header, info: MapMetaData, encoding: str = 'display'
) -> OccupancyGrid:
    """
    Convert a value map (row 0 = north) to an OccupancyGrid, min..max scaled to 0..100.

    `display`: the best cell is 100, the worst 0 (a constant map is all 0), for a colour
    ramp in RViz. `cost`: the reverse, best 0 and worst 100 (a constant map is all 0), as a
    costmap reads cells (100 = lethal), so a planner is drawn to the goal, not kept out.
    """
    if encoding not in VALUE_MAP_ENCODINGS:
        raise ValueError(
            f'unknown value map encoding {encoding!r}; use one of {", ".join(VALUE_MAP_ENCODINGS)}'
        )
    values = np.asarray(values, dtype=np.float64)
    low, high, span = values.min(), values.max(), np.ptp(values)
    if span == 0:
        return _scaled_grid(np.zeros_like(values), header, info)
    scaled = (values - low) if encoding == 'display' else (high - values)
    return _scaled_grid(scaled / span * PERCENT, header, info)


def magnitude_to_occupancy_grid(
    values: np.ndarray, header: Header, info: MapMetaData
) -> OccupancyGrid:
    """
    |values| (row 0 = north) scaled so the largest magnitude is 100 and 0 stays 0.

    The paper's |Z1| relation-map view.
    """
    magnitude = np.abs(np.asarray(values, dtype=np.float64))
    top = magnitude.max()
    return _scaled_grid(magnitude / top * PERCENT if top > 0 else magnitude, header, info)


def value_map_to_float32_multiarray(values: np.ndarray) -> Float32MultiArray:
    """
    Return exact values, row-major (height, width), in the OccupancyGrid's cell order.

    Exact values, row-major (height, width) in the OccupancyGrid's cell order (row 0 at
    the map origin, i.e. south), so index i matches value_map.data[i].
    """
    values = np.asarray(values, dtype=np.float32)[::-1]
    height, width = values.shape
    msg = Float32MultiArray()
    msg.layout.dim = [
        MultiArrayDimension(label='height', size=height, stride=height * width),
        MultiArrayDimension(label='width', size=width, stride=width),
    ]
    msg.layout.data_offset = 0
    msg.data = array.array('f', np.ascontiguousarray(values).tobytes())
    return msg


def float32_multiarray_to_value_map(msg: Float32MultiArray) -> np.ndarray:
    """Inverse of value_map_to_float32_multiarray: (H, W) float32, row 0 = north."""
    return multiarray_to_map(msg)


def cell_centre(cell: tuple[int, int], info: MapMetaData) -> tuple[float, float, float]:
    """(x, y, z) in the map frame of the centre of data-set cell (row, col), row 0 = north."""
    row, col = cell
    if not (0 <= row < info.height and 0 <= col < info.width):
        raise ValueError(f'cell {cell} is outside the {info.height}x{info.width} map')
    local = np.array(
        [(col + 0.5) * info.resolution, (info.height - 1 - row + 0.5) * info.resolution, 0.0]
    )
    p = info.origin.position
    x, y, z = _rotate(_quaternion(info.origin), local) + np.array([p.x, p.y, p.z])
    return float(x), float(y), float(z)


def cell_to_pose(
    cell: tuple[int, int], info: MapMetaData, frame_id: str, stamp: Time
) -> PoseStamped:
    """
    Return a goal at the centre of data-set cell (row, col), stamped `stamp`.

    Orientation is the identity in `frame_id` (facing the frame's +x, not the grid's east
    when the origin is rotated): the instruction names a place, not a heading.
    """
    pose = PoseStamped()
    pose.header.frame_id, pose.header.stamp = frame_id, stamp
    pose.pose.position.x, pose.pose.position.y, pose.pose.position.z = cell_centre(cell, info)
    pose.pose.orientation.w = 1.0
    return pose


def point_to_cell(x: float, y: float, info: MapMetaData) -> tuple[int, int] | None:
    """Data-set (row, col) of the cell holding map-frame point (x, y), or None off the map."""
    p = info.origin.position
    local = _rotate(
        _quaternion(info.origin) * np.array([-1, -1, -1, 1]), np.array([x - p.x, y - p.y, 0.0])
    )
    col = math.floor(local[0] / info.resolution)
    grid_row = math.floor(local[1] / info.resolution)
    if not (0 <= col < info.width and 0 <= grid_row < info.height):
        return None
    return info.height - 1 - grid_row, col
