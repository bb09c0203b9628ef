# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Conversions between grids / value maps and ROS messages. Pure functions, no node.

Orientation: a data-set grid's row 0 is the north (top) row, OccupancyGrid row 0 the south one
at the map origin (map_geometry.py, which also holds cell_centre and point_to_cell, says how).
"""

from __future__ import annotations

import array
import math

from builtin_interfaces.msg import Time
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import MapMetaData, OccupancyGrid
import numpy as np
from std_msgs.msg import Float32MultiArray, Header, MultiArrayDimension

# the ROS side reads the geometry through this module: convert.cell_centre, convert.point_to_cell
from ..core.map_geometry import cell_centre, multiarray_to_map, origin_quaternion
from ..core.map_geometry import point_to_cell  # noqa: F401

PERCENT = 100  # OccupancyGrid cell values for RViz: 0..100
# value_map cells: best = 100 (display) or best = 0 (cost, as a costmap reads it)
VALUE_MAP_ENCODINGS = ('display', 'cost')


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
    origin_quaternion(info.origin)


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

    Row 0 is at the map origin, i.e. south, so index i matches value_map.data[i].
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
