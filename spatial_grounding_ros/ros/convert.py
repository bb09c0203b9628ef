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
import sys

from builtin_interfaces.msg import Time
from geometry_msgs.msg import PoseStamped
from geometry_msgs.msg import Quaternion
from nav_msgs.msg import MapMetaData, OccupancyGrid
import numpy as np
from sensor_msgs.msg import Image
from std_msgs.msg import Float32MultiArray, Header, MultiArrayDimension

from ..core import instruction_hold
# the ROS side reads the geometry through this module: convert.cell_centre, convert.point_to_cell
from ..core.map_geometry import cell_centre, multiarray_to_map, origin_quaternion
from ..core.map_geometry import point_to_cell  # noqa: F401

PERCENT = 100  # OccupancyGrid cell values for RViz: 0..100
# value_map cells: best = 100 (display) or best = 0 (cost: the reverse ramp); neither is meant
# for a Nav2 costmap layer (docs/ros.md, "Feeding Nav2")
VALUE_MAP_ENCODINGS = ('display', 'cost')
# the goal's orientation: identity, toward the referent landmark, or the robot's own yaw
GOAL_HEADINGS = instruction_hold.GOAL_HEADINGS


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
    ramp in RViz. `cost`: the reverse, best 0 and worst 100 (a constant map is all 0), for
    a costmap colour scheme. Neither is a Nav2 costmap's input: a StaticLayer marks the cells
    at or above its lethal_threshold lethal, i.e. `cost`'s worst and `display`'s goal cell.
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
    cell: tuple[int, int],
    info: MapMetaData,
    frame_id: str,
    stamp: Time,
    yaw: float | None = None,
) -> PoseStamped:
    """
    Return a goal at the centre of data-set cell (row, col), stamped `stamp`.

    Orientation: `yaw` about z in `frame_id`; None is the identity (facing the frame's +x, not
    the grid's east when the origin is rotated): an instruction names a place, not a heading.
    """
    pose = PoseStamped()
    pose.header.frame_id, pose.header.stamp = frame_id, stamp
    pose.pose.position.x, pose.pose.position.y, pose.pose.position.z = cell_centre(cell, info)
    pose.pose.orientation = yaw_quaternion(0.0 if yaw is None else yaw)
    return pose


def value_map_to_image(values: np.ndarray, header: Header) -> Image:
    """
    Return exact values as a sensor_msgs/Image, 32FC1, north up.

    Image row r is data-set row r (row 0 = north, the top of the picture), i.e. OccupancyGrid
    row height-1-r: the rows of value_map_raw in reverse order. Column c is grid column c.
    """
    values = np.ascontiguousarray(np.asarray(values, dtype=np.float32))
    height, width = values.shape
    msg = Image(header=header, height=height, width=width, encoding='32FC1')
    msg.is_bigendian = int(sys.byteorder == 'big')
    msg.step = width * 4
    msg.data = array.array('B', values.tobytes())
    return msg


def image_to_value_map(msg: Image) -> np.ndarray:
    """Inverse of value_map_to_image: (H, W) float32, row 0 = north."""
    if msg.encoding != '32FC1':
        raise ValueError(f'expected a 32FC1 image, got {msg.encoding!r}')
    dtype = np.dtype('>f4' if msg.is_bigendian else '<f4')
    rows = np.frombuffer(bytes(msg.data), dtype=np.uint8).reshape(msg.height, msg.step)
    return rows[:, : msg.width * 4].copy().view(dtype).astype(np.float32)


def yaw_quaternion(yaw: float) -> Quaternion:
    """Return the rotation by `yaw` about z."""
    return Quaternion(z=math.sin(yaw / 2.0), w=math.cos(yaw / 2.0))


def quaternion_yaw(q: Quaternion) -> float:
    """Return the yaw (rotation about z) of an orientation, as tf2's getYaw."""
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
