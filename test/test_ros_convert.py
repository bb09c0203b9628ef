# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Message conversion (ros/convert.py): orientation, scaling, layouts and input checks.

Pure functions over message types: no node, no DDS.
"""

import math

import numpy as np
import pytest

pytest.importorskip('nav_msgs.msg', reason='ROS 2 message packages are not installed')

from spatial_grounding_ros.ros import convert  # noqa: E402
from std_msgs.msg import Header  # noqa: E402

HEADER = Header(frame_id='map')


def test_grid_round_trip_puts_data_set_row_0_at_the_largest_grid_row():
    grid = np.arange(12).reshape(3, 4)
    msg = convert.grid_to_occupancy_grid(grid, HEADER)
    assert (msg.info.height, msg.info.width) == (3, 4)
    # OccupancyGrid row 0 (first 4 values) is the data set's bottom (south) row
    assert list(msg.data[:4]) == [8, 9, 10, 11]
    assert list(msg.data[-4:]) == [0, 1, 2, 3]
    np.testing.assert_array_equal(convert.occupancy_grid_to_grid(msg, max_cells=12), grid)


def test_north_is_largest_y_and_east_largest_x():
    info = convert.map_info((4, 5), resolution=0.5, origin=(2.0, -3.0))
    assert convert.cell_centre((0, 0), info) == pytest.approx((2.25, -3 + 3.5 * 0.5, 0))
    assert convert.cell_centre((3, 4), info) == pytest.approx((2 + 4.5 * 0.5, -3 + 0.25, 0))
    ys = [convert.cell_centre((r, 0), info)[1] for r in range(4)]
    xs = [convert.cell_centre((0, c), info)[0] for c in range(5)]
    assert ys == sorted(ys, reverse=True) and xs == sorted(xs)


def test_rotated_origin_turns_the_grid():
    # yaw +90 degrees: the grid's east (+col) points along map +y, its north (-row) along -x
    info = convert.map_info((2, 3), resolution=1.0, origin=(10.0, 0.0), yaw=math.pi / 2)
    x0, y0, _ = convert.cell_centre((1, 0), info)  # south-west cell: local (0.5, 0.5)
    assert (x0, y0) == pytest.approx((9.5, 0.5))
    x1, y1, _ = convert.cell_centre((1, 2), info)
    assert (x1, y1) == pytest.approx((9.5, 2.5))
    x2, y2, _ = convert.cell_centre((0, 0), info)
    assert (x2, y2) == pytest.approx((8.5, 0.5))


@pytest.mark.parametrize('yaw', [0.0, 0.7, -2.5])
def test_point_to_cell_inverts_cell_centre(yaw):
    info = convert.map_info((3, 4), resolution=0.25, origin=(-1.0, 2.0), yaw=yaw)
    for row in range(3):
        for col in range(4):
            x, y, _ = convert.cell_centre((row, col), info)
            assert convert.point_to_cell(x, y, info) == (row, col)
    assert convert.point_to_cell(-100.0, -100.0, info) is None


def test_cell_to_pose_is_stamped_in_the_map_frame():
    info = convert.map_info((2, 2), resolution=2.0)
    stamp = Header().stamp
    stamp.sec = 5
    pose = convert.cell_to_pose((0, 1), info, 'odom', stamp)
    assert pose.header.frame_id == 'odom' and pose.header.stamp.sec == 5
    assert (pose.pose.position.x, pose.pose.position.y) == pytest.approx((3.0, 3.0))
    assert pose.pose.orientation.w == 1.0
    with pytest.raises(ValueError, match='outside'):
        convert.cell_to_pose((2, 0), info, 'map', stamp)


def test_value_map_is_scaled_to_0_100_in_grid_order():
    values = np.array([[3.0, -1.0], [1.0, 0.0]])  # row 0 = north
    msg = convert.value_map_to_occupancy_grid(values, HEADER, convert.map_info((2, 2)))
    assert list(msg.data) == [50, 25, 100, 0]
    flat = convert.value_map_to_occupancy_grid(
        np.full((2, 2), 7.0), HEADER, convert.map_info((2, 2))
    )
    assert list(flat.data) == [0, 0, 0, 0]


def test_cost_encoding_puts_the_best_cell_at_0_as_a_costmap_reads_it():
    """
    `value_map_encoding: cost`.

    The reverse of the display scale, best 0, worst 100 (lethal), so a planner reading value_map as
    a costmap is drawn to the goal.
    """
    values = np.array([[3.0, -1.0], [1.0, 0.0]])  # row 0 = north
    info = convert.map_info((2, 2))
    cost = convert.value_map_to_occupancy_grid(values, HEADER, info, encoding='cost')
    display = convert.value_map_to_occupancy_grid(values, HEADER, info, encoding='display')
    assert list(cost.data) == [50, 75, 0, 100]
    assert [c + d for c, d in zip(cost.data, display.data)] == [100] * 4
    flat = convert.value_map_to_occupancy_grid(np.full((2, 2), 7.0), HEADER, info, 'cost')
    assert list(flat.data) == [0, 0, 0, 0]
    with pytest.raises(ValueError, match="unknown value map encoding 'heat'"):
        convert.value_map_to_occupancy_grid(values, HEADER, info, encoding='heat')


def test_relation_map_is_magnitude_with_zero_kept():
    z1 = np.array([[-2.0, 0.0], [1.0, 0.5]])
    msg = convert.magnitude_to_occupancy_grid(z1, HEADER, convert.map_info((2, 2)))
    assert list(msg.data) == [50, 25, 100, 0]
    zero = convert.magnitude_to_occupancy_grid(np.zeros((2, 2)), HEADER, convert.map_info((2, 2)))
    assert list(zero.data) == [0, 0, 0, 0]


def test_float32_multiarray_layout_matches_the_occupancy_grid_order():
    values = np.arange(6, dtype=np.float32).reshape(2, 3) / 7  # not exactly representable
    msg = convert.value_map_to_float32_multiarray(values)
    dims = [(d.label, d.size, d.stride) for d in msg.layout.dim]
    assert dims == [('height', 2, 6), ('width', 3, 3)] and msg.layout.data_offset == 0
    np.testing.assert_array_equal(np.asarray(msg.data, np.float32), values[::-1].ravel())
    np.testing.assert_array_equal(convert.float32_multiarray_to_value_map(msg), values)


@pytest.mark.parametrize(
    'change, problem',
    [
        ({'width': 0}, 'width and height must be positive'),
        ({'height': 0}, 'width and height must be positive'),
        ({'width': 300, 'height': 300}, 'more than max_cells'),
        ({'resolution': float('nan')}, 'resolution nan'),
        ({'resolution': 0.0}, 'resolution 0.0'),
        ({'resolution': -1.0}, 'resolution -1.0'),
        ({'resolution': float('inf')}, 'resolution inf'),
    ],
)
def test_bad_map_info_is_named(change, problem):
    msg = convert.grid_to_occupancy_grid(np.zeros((3, 3), int), HEADER)
    for key, value in change.items():
        setattr(msg.info, key, value)
    with pytest.raises(ValueError, match=problem):
        convert.occupancy_grid_to_grid(msg, max_cells=1000)


def test_bad_origin_and_data_length_are_named():
    msg = convert.grid_to_occupancy_grid(np.zeros((3, 3), int), HEADER)
    msg.info.origin.orientation.w = 0.0
    with pytest.raises(ValueError, match='not a valid quaternion'):
        convert.occupancy_grid_to_grid(msg, max_cells=100)
    msg = convert.grid_to_occupancy_grid(np.zeros((3, 3), int), HEADER)
    msg.info.origin.position.x = float('nan')
    with pytest.raises(ValueError, match='origin position'):
        convert.occupancy_grid_to_grid(msg, max_cells=100)
    msg = convert.grid_to_occupancy_grid(np.zeros((3, 3), int), HEADER)
    msg.data = [0] * 8
    with pytest.raises(ValueError, match='8 values'):
        convert.occupancy_grid_to_grid(msg, max_cells=100)
