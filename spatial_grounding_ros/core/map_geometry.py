# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Where the cells of a grid map are, without ROS: shared by ros/convert.py and bags.py.

Orientation (REP 103, and the package's design): a data-set grid's row 0 is the north (top)
row, while an OccupancyGrid's row index grows with +y (row 0 sits at the map origin). So
data-set row r is OccupancyGrid row height-1-r, and "northernmost" means largest y in the map
frame. Cell centres go through the full origin pose (position and rotation) and the resolution.

Every function is duck-typed on the message fields it reads (`info` is an OccupancyGrid's
MapMetaData), so it works on rclpy messages and on rosbags' decoded ones alike.
"""

from __future__ import annotations

import math

import numpy as np


def origin_quaternion(pose) -> np.ndarray:
    """Return (x, y, z, w) of a pose's orientation, normalised; ValueError if not a rotation."""
    o = pose.orientation
    q = np.array([o.x, o.y, o.z, o.w], dtype=np.float64)
    norm = float(np.linalg.norm(q))
    if not np.isfinite(q).all() or norm < 1e-9:
        raise ValueError(f'map origin orientation {q.tolist()} is not a valid quaternion')
    return q / norm


def cross(u, v) -> np.ndarray:
    """Return u x v of two 3-vectors (np.cross's generality made it a tenth of a goal's time)."""
    return np.array(
        [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    )


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate the 3-vector v by the unit quaternion q = (x, y, z, w)."""
    u, w = q[:3], q[3]
    t = 2.0 * cross(u, v)
    return v + w * t + cross(u, t)


def cell_centre(cell: tuple[int, int], info) -> tuple[float, float, float]:
    """Return (x, y, z) in the map frame of the centre of data-set cell (row, col), row 0 north."""
    row, col = cell
    if not (0 <= row < info.height and 0 <= col < info.width):
        raise ValueError(f'cell {cell} is outside the {info.height}x{info.width} map')
    local = np.array(
        [(col + 0.5) * info.resolution, (info.height - 1 - row + 0.5) * info.resolution, 0.0]
    )
    p = info.origin.position
    x, y, z = rotate(origin_quaternion(info.origin), local) + np.array([p.x, p.y, p.z])
    return float(x), float(y), float(z)


def point_to_cell(x: float, y: float, info) -> tuple[int, int] | None:
    """Return data-set (row, col) of the cell holding map-frame point (x, y), None off the map."""
    p = info.origin.position
    inverse = origin_quaternion(info.origin) * np.array([-1, -1, -1, 1])
    local = rotate(inverse, np.array([x - p.x, y - p.y, 0.0]))
    col = math.floor(local[0] / info.resolution)
    grid_row = math.floor(local[1] / info.resolution)
    if not (0 <= col < info.width and 0 <= grid_row < info.height):
        return None
    return info.height - 1 - grid_row, col


def multiarray_to_map(msg) -> np.ndarray:
    """Convert a (height, width) Float32MultiArray in OccupancyGrid cell order to (H, W)."""
    if len(msg.layout.dim) != 2:
        raise ValueError(
            f'expected a 2-D Float32MultiArray layout, got {len(msg.layout.dim)} dims'
        )
    h, w = msg.layout.dim[0].size, msg.layout.dim[1].size
    data = np.asarray(msg.data, dtype=np.float32)[msg.layout.data_offset:]
    if data.size != h * w:
        raise ValueError(f'{data.size} values for a {h}x{w} layout')
    return data.reshape(h, w)[::-1].copy()
