# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The entity mapper over real DDS: a SLAM map and landmarks -> entity_map -> the grounder's goal.

A synthetic SLAM map (0.05 m cells, origin (-1.5, 2.0), walls, a thin partition, unknown
regions) and landmarks as markers (a desk of 3x2 cells, a fridge, a printer as a text marker,
two chairs) go through the entity_mapper node at 0.25 m cells and the grounder node on the
office table; offset, extreme, metric and footprint instructions give a goal_pose within half a
cell of the true metric goal. Also: landmarks_file, DELETE/DELETEALL, warnings, the config and
launch files.

Run as a script, it draws docs/slam_to_goal.png from what the nodes published:
    .venv/bin/python test/test_entity_mapper.py docs/slam_to_goal.png
"""

from __future__ import annotations

import math
from pathlib import Path
import sys

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]
OFFICE = REPO / 'config' / 'entities_office.yaml'
RES, CELL, K = 0.05, 0.25, 5  # SLAM resolution, entity cell size, SLAM cells per entity cell
H, W = 10, 12  # entity cells
ORIGIN = (-1.5, 2.0)
FLOOR, WALL, DESK, CHAIR, PRINTER, FRIDGE, UNKNOWN = 0, 1, 2, 3, 4, 9, 14
# the expected entity map, data-set order (row 0 north)
EXPECTED = np.array(
    [
        [1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1],
        [1, 0, 0, 0, 0, 0, 1, 0, 0, 14, 14, 1],
        [1, 0, 0, 3, 0, 0, 1, 0, 0, 14, 14, 1],
        [1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1],
        [1, 0, 9, 0, 0, 4, 0, 0, 0, 0, 0, 1],
        [1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1],
        [1, 1, 0, 0, 0, 0, 0, 0, 3, 0, 0, 1],
        [1, 0, 2, 2, 2, 0, 0, 0, 0, 0, 0, 1],
        [1, 0, 2, 2, 2, 0, 0, 0, 0, 0, 0, 1],
        [1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1],
    ]
)


def slam_map() -> np.ndarray:
    """Return the SLAM map's cells, OccupancyGrid order (row 0 at the origin, south)."""
    slam = np.zeros((H * K, W * K), np.int8)
    slam[0, :] = slam[-1, :] = slam[:, 0] = slam[:, -1] = 100  # walls one SLAM cell thick
    slam[7 * K:9 * K, 9 * K:11 * K] = -1  # a room not yet seen: unknown
    slam[2 * K:2 * K + 2, 9 * K:10 * K] = -1  # 10 of 25 unknown: still floor
    slam[6 * K:9 * K, 6 * K + 2] = 100  # a partition one SLAM cell thick
    slam[3 * K + 1, K + 3] = 70  # one occupied SLAM cell makes its entity cell a wall
    slam[4 * K:5 * K, 8 * K:9 * K] = 40  # below occupied_threshold: floor
    return slam


def place(row: float, col: float) -> tuple[float, float]:
    """Map-frame (x, y) of a point in entity cells, OccupancyGrid order (row 0 south)."""
    return ORIGIN[0] + (col + 0.5) * CELL, ORIGIN[1] + (row + 0.5) * CELL


def centre_of(cell: tuple[int, int]) -> tuple[float, float]:
    """Map-frame centre of data-set cell (row, col), row 0 north."""
    return place(H - 1 - cell[0], cell[1])


# (name, marker type, OccupancyGrid row, col, footprint x, y); a few centimetres off the
# cell centres, as measured places are
def markers_spec():
    from visualization_msgs.msg import Marker

    return [
        ('desk', Marker.CUBE, 1.5, 3.0, 0.75, 0.5),  # 3x2 cells
        ('refrigerator', Marker.CYLINDER, 5.1, 1.9, 0.0, 0.0),  # an alias of fridge
        ('printer', Marker.TEXT_VIEW_FACING, 5.08, 4.96, 0.0, 0.0),  # text: one cell
        ('chair', Marker.CUBE, 3.0, 8.1, 0.25, 0.25),
        ('chairs', Marker.CUBE, 7.0, 2.95, 0.2, 0.2),  # a plural names the kind too
    ]


def markers(frame_id='map'):
    from visualization_msgs.msg import Marker, MarkerArray

    out = MarkerArray()
    for i, (name, kind, row, col, sx, sy) in enumerate(markers_spec()):
        m = Marker(type=kind, action=Marker.ADD, ns='landmarks', id=i, text=name)
        m.header.frame_id = frame_id
        m.pose.position.x, m.pose.position.y = place(row, col)
        m.pose.orientation.w = 1.0
        m.scale.x, m.scale.y, m.scale.z = sx, sy, 0.3
        out.markers.append(m)
    return out


def slam_message(stamp: int = 1):
    from spatial_grounding_ros.ros import convert
    from std_msgs.msg import Header

    # convert's grids are data-set order: flip so that the message holds slam_map() as it is
    msg = convert.grid_to_occupancy_grid(
        slam_map()[::-1], Header(frame_id='map'), convert.map_info((H * K, W * K), RES, ORIGIN)
    )
    msg.header.stamp.sec = stamp
    return msg


def make_probe(context, namespace):
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import OccupancyGrid
    from rclpy.node import Node
    from spatial_grounding_ros.ros.qos import LATCHED
    from std_msgs.msg import String
    from visualization_msgs.msg import MarkerArray

    class Probe(Node):
        def __init__(self):
            super().__init__('mapper_probe', namespace=namespace, context=context)
            self.entity_maps, self.goals, self.diagnostics = [], [], []
            sub = self.create_subscription
            self.entity_sub = sub(OccupancyGrid, 'entity_map', self.entity_maps.append, LATCHED)
            self.goal_sub = sub(PoseStamped, 'goal_pose', self.goals.append, 10)
            self.diagnostics_sub = sub(DiagnosticArray, '/diagnostics', self.on_diagnostics, 100)
            self.map_pub = self.create_publisher(OccupancyGrid, 'map', LATCHED)
            self.landmarks_pub = self.create_publisher(MarkerArray, 'landmarks', 10)
            self.instruction_pub = self.create_publisher(String, 'instruction', 10)

        def on_diagnostics(self, msg):
            self.diagnostics += [s for s in msg.status if s.name.startswith(namespace + '/')]

        def hears_diagnostics(self, nodes: int = 1) -> bool:
            """Whether /diagnostics is matched to every publisher, `nodes` of them ours."""
            publishers = self.get_publishers_info_by_topic('/diagnostics')
            ours = [p for p in publishers if p.node_namespace == namespace]
            # matched, not just seen: a WARN sent before the match would be lost
            return (
                len(ours) >= nodes
                and self.diagnostics_sub.get_publisher_count() >= len(publishers)
            )

        def grid(self) -> np.ndarray | None:
            from spatial_grounding_ros.ros import convert

            if not self.entity_maps:
                return None
            return convert.occupancy_grid_to_grid(self.entity_maps[-1], 10**6)

        def said(self, part: str, level, needle: str = '') -> list[str]:
            return [
                s.message
                for s in self.diagnostics
                if s.name.endswith(f': {part}') and s.level == level and needle in s.message
            ]

    return Probe()


def mapper(graph, namespace, **parameters):
    from rclpy.parameter import Parameter
    from spatial_grounding_ros.ros.entity_mapper_node import EntityMapperNode

    return graph.add(
        EntityMapperNode(
            context=graph.context,
            namespace=namespace,
            parameter_overrides=[Parameter(k, value=v) for k, v in parameters.items()],
        )
    )


def grounder(graph, namespace):
    from rclpy.parameter import Parameter
    from spatial_grounding_ros.ros.grounder_node import GrounderNode

    try:
        node = GrounderNode(
            context=graph.context,
            namespace=namespace,
            parameter_overrides=[
                Parameter('entity_table', value=str(OFFICE)),
                Parameter('torch_threads', value=0),
            ],
        )
    except ValueError as exc:
        if 'checkpoint was trained on' not in str(exc):
            raise
        pytest.skip(f'the grounder node does not read a table of its own yet: {exc}')
    return graph.add(node)


def held(probe, namespace) -> bool:
    """Whether the grounder said it holds the latest entity map (its stamp)."""
    from diagnostic_msgs.msg import DiagnosticStatus

    if not probe.entity_maps:
        return False
    stamp = probe.entity_maps[-1].header.stamp
    want = {'stamp_sec': str(stamp.sec), 'stamp_nanosec': str(stamp.nanosec)}
    return any(
        s.name == f'{namespace}/spatial_grounder: entity_map'
        and s.level == DiagnosticStatus.OK
        and want.items() <= {v.key: v.value for v in s.values}.items()
        for s in probe.diagnostics
    )


def run_pipeline(graph, namespace, instructions):
    """
    Start the mapper, the grounder and a probe; send the SLAM map, the markers, `instructions`.

    Returns the probe (its entity maps, goals and diagnostics) and the goals per instruction.
    """
    mapper(graph, namespace)
    grounder(graph, namespace)
    probe = graph.add(make_probe(graph.context, namespace))
    assert graph.wait_for(
        lambda: probe.landmarks_pub.get_subscription_count() > 0
        and probe.map_pub.get_subscription_count() > 0
        and probe.instruction_pub.get_subscription_count() > 0
        and probe.goal_sub.get_publisher_count() > 0
        and probe.entity_sub.get_publisher_count() > 0
        and probe.hears_diagnostics(nodes=2),
    ), 'the nodes never matched the probe'
    probe.map_pub.publish(slam_message())
    assert graph.wait_for(lambda: probe.grid() is not None), 'no entity_map'
    probe.landmarks_pub.publish(markers())
    assert graph.wait_for(
        lambda: np.array_equal(probe.grid(), EXPECTED) and held(probe, namespace), timeout=15
    ), probe.grid()
    goals = {}
    from std_msgs.msg import String

    for text in instructions:
        before = len(probe.goals)
        probe.instruction_pub.publish(String(data=text))
        assert graph.wait_for(lambda: len(probe.goals) > before), (
            text,
            [s.message for s in probe.diagnostics[-3:]],
        )
        goals[text] = probe.goals[-1]
    return probe, goals


INSTRUCTIONS = {  # instruction -> its goal cell (data-set row, col) on EXPECTED
    'reach the cell two below the printer': (6, 5),
    # a chair is solid: the free cell beside it (its four sides tie; the first in row order)
    'reach the westernmost chair': (1, 3),
    # (three below it is the desk, solid: declined as goal-on-obstacle since traversal)
    'reach the cell two below the fridge': (6, 2),
    # metres, at the entity map's 0.25 m cells, from one-cell landmarks' centres
    'go one metre east of the printer': (4, 9),
    'stop half a metre north of the fridge': (2, 2),
    # the desk covers rows 7-8, columns 2-4: "above" it is above the middle of its top row
    'reach the cell above the desk': (6, 3),
}


def test_slam_map_and_markers_to_entity_map_to_goal_pose(ros_context):
    """The whole chain over DDS, and the entity map it goes through."""
    namespace = '/mapper_' + __import__('secrets').token_hex(3)
    probe, goals = run_pipeline(ros_context, namespace, INSTRUCTIONS)
    entity = probe.entity_maps[-1]
    # aligned with the SLAM map: its frame and origin, 0.25 m cells covering it
    assert entity.header.frame_id == 'map'
    assert entity.info.resolution == pytest.approx(CELL)
    assert (entity.info.width, entity.info.height) == (W, H)
    origin = entity.info.origin.position
    assert (origin.x, origin.y) == pytest.approx(ORIGIN)
    grid = probe.grid()
    assert (grid[1:3, 9:11] == UNKNOWN).all()  # the unseen room
    assert grid[7, 9] == FLOOR  # 10 of its 25 SLAM cells unknown: floor
    assert (grid[0] == WALL).all() and (grid[:, 0] == WALL).all()
    assert (grid[1:4, 6] == WALL).all()  # the partition, thinner than a cell
    assert grid[6, 1] == WALL  # a single occupied SLAM cell
    assert grid[5, 8] == FLOOR  # 40 < occupied_threshold
    assert (grid[7:9, 2:5] == DESK).all() and (grid == DESK).sum() == 6  # its footprint
    for text, cell in INSTRUCTIONS.items():
        p = goals[text].pose.position
        x, y = centre_of(cell)
        assert math.hypot(p.x - x, p.y - y) <= CELL / 2, (text, p.x, p.y, x, y)
        assert goals[text].header.frame_id == 'map'


def test_marker_actions_frames_and_unknown_names(ros_context):
    """DELETE removes one marker, DELETEALL all; another frame and an unknown name: WARN."""
    from diagnostic_msgs.msg import DiagnosticStatus
    from visualization_msgs.msg import Marker, MarkerArray

    namespace = '/mapper_' + __import__('secrets').token_hex(3)
    graph = ros_context
    mapper(graph, namespace)
    probe = graph.add(make_probe(graph.context, namespace))
    assert graph.wait_for(
        lambda: probe.landmarks_pub.get_subscription_count() > 0
        and probe.map_pub.get_subscription_count() > 0
        and probe.hears_diagnostics()
    )
    probe.map_pub.publish(slam_message())
    probe.landmarks_pub.publish(markers())
    assert graph.wait_for(lambda: np.array_equal(probe.grid(), EXPECTED))
    delete = MarkerArray(markers=[Marker(ns='landmarks', id=0, action=Marker.DELETE)])
    probe.landmarks_pub.publish(delete)
    assert graph.wait_for(lambda: (probe.grid() == DESK).sum() == 0)
    assert (probe.grid() == CHAIR).sum() == 2
    probe.landmarks_pub.publish(MarkerArray(markers=[Marker(action=Marker.DELETEALL)]))
    assert graph.wait_for(lambda: set(np.unique(probe.grid())) == {FLOOR, WALL, UNKNOWN})
    odd = markers()
    odd.markers[0].text = 'piano'
    odd.markers[1].header.frame_id = 'odom'
    probe.landmarks_pub.publish(odd)
    warn = DiagnosticStatus.WARN
    assert graph.wait_for(lambda: probe.said('landmarks', warn, "'piano' is not a kind"))
    assert probe.said('landmarks', warn, "in frame 'odom', not the map's 'map'")
    assert graph.wait_for(lambda: (probe.grid() == PRINTER).sum() == 1)
    assert (probe.grid() == DESK).sum() == 0 and (probe.grid() == FRIDGE).sum() == 0


def test_landmarks_file(ros_context, tmp_path):
    """Landmarks that do not move come from a YAML file: name, x, y, size (a number or [x, y])."""
    import yaml

    spec = [
        {'name': 'desk', 'x': place(1.5, 3.0)[0], 'y': place(1.5, 3.0)[1], 'size': [0.75, 0.5]},
        {'name': 'fridge', 'x': place(5, 2)[0], 'y': place(5, 2)[1]},
        {'name': 'copier', 'x': place(5, 5)[0], 'y': place(5, 5)[1], 'size': 0.1},
        {'name': 'seat', 'x': place(3, 8)[0], 'y': place(3, 8)[1], 'size': 0.25},
        {'name': 'chair', 'x': place(7, 3)[0], 'y': place(7, 3)[1]},
    ]
    path = tmp_path / 'landmarks.yaml'
    path.write_text(yaml.safe_dump({'frame_id': 'map', 'landmarks': spec}))
    namespace = '/mapper_' + __import__('secrets').token_hex(3)
    graph = ros_context
    mapper(graph, namespace, landmarks_file=str(path))
    probe = graph.add(make_probe(graph.context, namespace))
    assert graph.wait_for(lambda: probe.map_pub.get_subscription_count() > 0)
    probe.map_pub.publish(slam_message())
    assert graph.wait_for(lambda: np.array_equal(probe.grid(), EXPECTED)), probe.grid()


@pytest.mark.parametrize(
    'content, needle',
    [
        ('landmarks: [{name: desk, x: 1.0}]', 'landmark 0'),
        ('places: []', 'holds `landmarks:`'),
        ('landmarks: [{name: desk, x: .nan, y: 0}]', 'non-finite'),
    ],
)
def test_bad_landmarks_file_is_a_start_up_error(tmp_path, content, needle):
    from spatial_grounding_ros.ros.entity_mapper_node import read_landmarks_file

    path = tmp_path / 'bad.yaml'
    path.write_text(content)
    with pytest.raises(ValueError, match=needle):
        read_landmarks_file(path)


def test_cells_finer_than_the_slam_map_read_the_cell_under_their_centre():
    from spatial_grounding_ros.ros import convert
    from spatial_grounding_ros.ros.entity_mapper_node import entity_cells, entity_info

    slam = np.array([[0, 100], [-1, 0]], np.int8)
    info = entity_info(convert.map_info(slam.shape, 1.0), 0.5)
    assert (info.width, info.height) == (4, 4)
    cells = entity_cells(slam, 1.0, info, (0, 1, 14), 65)
    assert cells.tolist() == [[0, 0, 1, 1], [0, 0, 1, 1], [14, 14, 0, 0], [14, 14, 0, 0]]


def test_office_table_has_unknown_as_an_obstacle():
    from spatial_grounding_ros.core.entities import EntityTable

    table = EntityTable.from_yaml(OFFICE)
    assert table.names.index('unknown') == 14 and 14 in table.obstacles
    assert table.index('wall') in table.obstacles


def test_params_file_and_launch_file():
    """config/entity_mapper.yaml is the declared defaults; the launch file starts the node."""
    import yaml

    from spatial_grounding_ros.ros.entity_mapper_node import NODE_NAME, PARAMETERS
    from test_ros_config import check_default_params_file, check_our_node, launch_parts, lc

    params = yaml.safe_load((REPO / 'config' / 'entity_mapper.yaml').read_text())
    assert params == {
        f'/**/{NODE_NAME}': {'ros__parameters': {p.name: p.default for p in PARAMETERS}}
    }
    arguments, [node] = launch_parts('entity_mapper.launch.py')
    assert set(arguments) == {'namespace', 'params_file', 'map_topic', 'use_sim_time', 'log_level'}
    check_default_params_file(arguments['params_file'], 'entity_mapper.yaml')
    overrides = check_our_node(node, 'entity_mapper', 'params_file')
    assert overrides == {'use_sim_time': lc('use_sim_time')}
    assert node['remappings'] == [['map', lc('map_topic')]]


def draw(path: str) -> None:
    """Run the chain and draw what RViz would show: SLAM map, entity cells, landmarks, goal."""
    sys.path.insert(0, str(REPO / 'test'))
    from conftest import RosGraph
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from spatial_grounding_ros.core.entities import EntityTable
    from spatial_grounding_ros.studies.plots import save

    text = 'reach the cell two below the printer'
    graph = RosGraph()
    try:
        probe, goals = run_pipeline(graph, '/mapper_figure', [text])
        grid = probe.grid()
    finally:
        graph.close()
    table = EntityTable.from_yaml(OFFICE)
    x0, y0 = ORIGIN
    extent = (x0, x0 + W * CELL, y0, y0 + H * CELL)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.8))
    slam = slam_map().astype(float)
    shade = np.where(slam < 0, 0.5, 1.0 - slam / 100.0)  # map_server's trinary look
    for ax in axes:
        ax.set_xlabel('x (m), frame map')
        ax.set_ylabel('y (m)')
    axes[0].imshow(shade, cmap='gray', vmin=0, vmax=1, origin='lower', extent=extent)
    axes[0].set_title('map (SLAM, 0.05 m) + landmarks (MarkerArray)')
    for name, _, row, col, sx, sy in markers_spec():
        x, y = place(row, col)
        sx, sy = sx or 0.12, sy or 0.12
        axes[0].add_patch(
            plt.Rectangle((x - sx / 2, y - sy / 2), sx, sy, fc='tab:orange', alpha=0.6)
        )
        axes[0].text(x, y + sy / 2 + 0.03, name, ha='center', va='bottom', fontsize=7)
    colours = np.full(grid.shape + (3,), 0.95)
    colours[grid == WALL] = (0.15, 0.15, 0.15)
    colours[grid == UNKNOWN] = (0.6, 0.6, 0.75)
    landmark = (grid != FLOOR) & (grid != WALL) & (grid != UNKNOWN)
    colours[landmark] = (0.95, 0.75, 0.45)
    axes[1].imshow(colours, extent=extent)  # data-set order: row 0 north, at the top
    for (r, c), kind in np.ndenumerate(grid):
        if landmark[r, c] or kind == UNKNOWN:
            x, y = centre_of((r, c))
            axes[1].text(x, y, table.names[kind][:6], ha='center', va='center', fontsize=6)
    axes[1].set_title('entity_map (0.25 m) + goal_pose')
    p = goals[text].pose.position
    for ax in axes:
        ax.annotate(
            '', (p.x + 0.25, p.y), (p.x - 0.02, p.y), arrowprops={'color': 'red', 'width': 2}
        )
        ax.plot(p.x, p.y, 'o', color='red', ms=4)
    fig.suptitle(f"'{text}' -> goal_pose ({p.x:.3f}, {p.y:.3f}) in map")
    print(save(fig, path, dpi=90))


if __name__ == '__main__':
    draw(sys.argv[1] if len(sys.argv) > 1 else str(REPO / 'docs' / 'slam_to_goal.png'))
