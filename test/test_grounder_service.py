# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The grounder node's honest answers over real DDS, with the packaged default checkpoint.

The ground_instruction service (through GroundingClient) and the topics: a decline sends no
goal and a WARN diagnostic naming its reason; an instruction that waited longer than
instruction_timeout is dropped; goal_heading, goal_stamp, value_map_image and the 1 Hz status.
"""

import math

import numpy as np
import pytest

pytest.importorskip('rclpy', reason='rclpy is not installed')
pytest.importorskip('spatial_grounding_interfaces', reason='make setup builds the interfaces')

from conftest import WAIT  # noqa: E402, I100
from diagnostic_msgs.msg import DiagnosticStatus  # noqa: E402
from geometry_msgs.msg import PoseStamped  # noqa: E402
from grounder_helpers import make_probe, PUDDLEWORLD_TABLE, unique_namespace  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from spatial_grounding_ros.grounder import Grounder  # noqa: E402
from spatial_grounding_ros.ros import convert  # noqa: E402
from spatial_grounding_ros.ros.grounder_node import GrounderNode  # noqa: E402
from spatial_grounding_ros.ros.grounding_client import GroundingClient  # noqa: E402
from std_msgs.msg import Header  # noqa: E402

NAMESPACE = unique_namespace('grounder_service_test')
ROCK = 8
ABOVE_ROCK = 'reach the cell above the rock'


def rock_map(cell=(2, 5), size=8):
    grid = np.zeros((size, size), dtype=np.int64)
    grid[cell] = ROCK
    return grid


@pytest.fixture(scope='module')
def reference():
    return Grounder.from_checkpoint()


@pytest.fixture(scope='module')
def nodes(ros_module_context):
    graph = ros_module_context
    grounder = graph.add(
        GrounderNode(
            context=graph.context,
            namespace=NAMESPACE,
            parameter_overrides=[Parameter('torch_threads', value=0), PUDDLEWORLD_TABLE],
        )
    )
    probe = graph.add(make_probe(graph.context, NAMESPACE, grounder.get_fully_qualified_name()))
    assert graph.wait_for(probe.connected), 'probe and grounder never matched'
    # a busy machine may be slow to answer: every call waits as long as the graph waits
    client = GroundingClient(NAMESPACE, context=graph.context, timeout=WAIT)
    assert client.wait_for_server(), 'no ground_instruction service'
    yield graph, grounder, probe, client
    client.close()


def set_params(grounder, **values):
    results = grounder.set_parameters([Parameter(k, value=v) for k, v in values.items()])
    assert all(r.successful for r in results), results


def hold(nodes, grid):
    graph, grounder, probe, _ = nodes
    message = probe.publish_map(grid)
    assert graph.wait_for(lambda: probe.holds(message)), 'no OK diagnostic for the map'
    return message


def yaw(pose: PoseStamped) -> float:
    return convert.quaternion_yaw(pose.pose.orientation)


def test_service_without_a_map_answers_the_error(nodes):
    graph, grounder, probe, client = nodes
    assert grounder.grid is None  # the module's first test: no map sent yet
    answer = client.ground(ABOVE_ROCK)
    assert not answer.success and 'no valid entity_map is held' in answer.reason
    assert answer.goal is None


def test_service_answers_on_the_held_map(nodes, reference):
    graph, grounder, probe, client = nodes
    grid = rock_map()
    message = hold(nodes, grid)
    expected = reference.ground(grid, ABOVE_ROCK)
    answer = client.ground(ABOVE_ROCK)
    assert answer.success and answer.reason == '', answer
    assert answer.confidence == pytest.approx(expected.confidence, rel=1e-5)
    info = convert.map_info(grid.shape)
    position = answer.goal.pose.position
    assert (position.x, position.y) == pytest.approx(convert.cell_centre(expected.goal, info)[:2])
    assert answer.goal.header.stamp == message.header.stamp
    assert answer.goal.header.frame_id == 'map'
    assert len(answer.alternatives) == len(expected.alternatives) > 0
    for (pose, score), (cell, probability) in zip(answer.alternatives, expected.alternatives):
        assert score == pytest.approx(probability, rel=1e-4, abs=1e-7)
        assert convert.point_to_cell(pose.pose.position.x, pose.pose.position.y, info) == cell


def test_service_grounds_the_map_in_the_request(nodes, reference):
    graph, grounder, probe, client = nodes
    grid = rock_map(cell=(6, 1))
    info = convert.map_info(grid.shape, resolution=0.5, origin=(3.0, -2.0))
    request_map = convert.grid_to_occupancy_grid(grid, Header(frame_id='odom'), info)
    request_map.header.stamp.sec = 777
    expected = reference.ground(grid, ABOVE_ROCK)
    held = grounder.map_msg
    answer = client.ground(ABOVE_ROCK, entity_map=request_map)
    assert answer.success, answer
    assert answer.goal.header.frame_id == 'odom' and answer.goal.header.stamp.sec == 777
    position = answer.goal.pose.position
    assert (position.x, position.y) == pytest.approx(convert.cell_centre(expected.goal, info)[:2])
    assert grounder.map_msg is held  # the service leaves the held map alone


def test_service_declines_and_refuses_bad_input(nodes):
    graph, grounder, probe, client = nodes
    hold(nodes, rock_map())  # the last call grounds on the held map, whichever test ran before
    answer = client.ground(ABOVE_ROCK, entity_map=np.zeros((6, 6), dtype=np.int64))
    assert not answer.success and answer.reason == 'referent-missing: rock', answer
    assert answer.goal is None and 0 <= answer.confidence <= 1
    assert not client.ground('   ').success
    assert client.ground('   ').reason == 'instruction is empty'
    bad = convert.grid_to_occupancy_grid(rock_map(), Header(frame_id='map'))
    bad.data = bad.data[:-1]
    answer = client.ground(ABOVE_ROCK, entity_map=bad)
    assert not answer.success and 'map data has 63 values' in answer.reason
    # the node still answers
    assert client.ground(ABOVE_ROCK).success


def test_decline_sends_no_goal_and_a_warning_naming_the_reason(nodes):
    graph, grounder, probe, client = nodes
    hold(nodes, np.zeros((6, 6), dtype=np.int64))
    before = probe.counts()
    probe.publish_instruction(ABOVE_ROCK)
    assert graph.wait_for(lambda: probe.new('diagnostics', before))
    [status] = probe.new('diagnostics', before)
    assert status.level == DiagnosticStatus.WARN, status
    assert 'referent-missing: rock' in status.message and 'no goal sent' in status.message
    assert {v.key: v.value for v in status.values}['reason'] == 'referent-missing: rock'
    assert status.hardware_id == grounder.get_fully_qualified_name()
    # goal_pose is one reliable, ordered stream: a goal for the decline would come first
    hold(nodes, rock_map())
    probe.publish_instruction(ABOVE_ROCK)
    assert graph.wait_for(lambda: probe.new('goals', before))
    assert graph.wait_for(lambda: len(probe.new('diagnostics', before)) >= 3)
    assert len(probe.new('goals', before)) == 1


def test_an_expired_instruction_never_fires_on_a_later_map(nodes):
    graph, grounder, probe, client = nodes
    set_params(grounder, instruction_timeout=0.2)
    try:
        bad = convert.grid_to_occupancy_grid(rock_map(), Header(frame_id='map'))
        bad.data = bad.data[:-1]
        probe.publish_map(message=bad)  # a rejected map drops the held one
        assert graph.wait_for(lambda: grounder.grid is None)
        before = probe.counts()
        probe.publish_instruction(ABOVE_ROCK)
        assert graph.wait_for(
            lambda: any('expired' in s.message for s in probe.new('diagnostics', before))
        ), 'no expiry diagnostic'
        [expired] = [s for s in probe.new('diagnostics', before) if 'expired' in s.message]
        assert expired.level == DiagnosticStatus.WARN and ABOVE_ROCK in expired.message
        assert not grounder.hold.pending
        hold(nodes, rock_map())
        # a map, then a new instruction: exactly one goal, the new instruction's
        probe.publish_instruction('reach the cell below the rock')
        assert graph.wait_for(lambda: probe.new('goals', before))
        [goal] = probe.new('goals', before)
        info = convert.map_info((8, 8))
        assert convert.point_to_cell(goal.pose.position.x, goal.pose.position.y, info) == (3, 5)
    finally:
        set_params(grounder, instruction_timeout=30.0)


def test_goal_heading_face_referent_and_keep(nodes, reference):
    graph, grounder, probe, client = nodes
    grid = rock_map()
    hold(nodes, grid)
    try:
        set_params(grounder, goal_heading='face_referent')
        before = probe.counts()
        probe.publish_instruction(ABOVE_ROCK)  # goal (1, 5), the rock (2, 5) south of it
        assert graph.wait_for(lambda: probe.new('goals', before))
        [goal] = probe.new('goals', before)
        assert reference.ground(grid, ABOVE_ROCK).referent == (2, 5)
        assert yaw(goal) == pytest.approx(-math.pi / 2)
        west = client.ground('reach the cell right of the rock')  # (2, 6): the rock is west
        assert abs(yaw(west.goal)) == pytest.approx(math.pi)
        set_params(grounder, goal_heading='keep')
        assert yaw(client.ground(ABOVE_ROCK).goal) == 0.0  # no robot_pose yet: identity
        pose = PoseStamped(header=Header(frame_id='map'))
        pose.pose.orientation = convert.yaw_quaternion(1.0)
        probe.robot_pose_pub.publish(pose)
        assert graph.wait_for(lambda: grounder.robot_yaw is not None)
        assert yaw(client.ground(ABOVE_ROCK).goal) == pytest.approx(1.0)
    finally:
        set_params(grounder, goal_heading='identity')


def test_goal_stamp_now(nodes):
    graph, grounder, probe, client = nodes
    message = hold(nodes, rock_map())
    try:
        set_params(grounder, goal_stamp='now')
        start = grounder.get_clock().now().nanoseconds
        answer = client.ground(ABOVE_ROCK)
        stamp = answer.goal.header.stamp
        assert stamp.sec * 10**9 + stamp.nanosec >= start > message.header.stamp.sec * 10**9
    finally:
        set_params(grounder, goal_stamp='map')


def test_value_map_image_is_north_up_with_the_maps_header(nodes, reference):
    graph, grounder, probe, client = nodes
    grid = rock_map(cell=(5, 2))
    message = hold(nodes, grid)
    before = probe.counts()
    probe.publish_instruction(ABOVE_ROCK)
    assert graph.wait_for(
        lambda: probe.new('images', before) and probe.new('value_maps', before)
    )
    image, value_map = probe.new('images', before)[-1], probe.new('value_maps', before)[-1]
    assert image.header == value_map.header and image.header.stamp == message.header.stamp
    assert (image.height, image.width, image.encoding) == (8, 8, '32FC1')
    assert image.step == 8 * 4
    values = convert.image_to_value_map(image)
    expected = reference.ground(grid, ABOVE_ROCK).values
    np.testing.assert_allclose(values, expected, rtol=1e-5, atol=1e-5)  # row 0 = north
    best = np.unravel_index(np.argmax(values), values.shape)
    assert best == (4, 2)  # the first image row is the northernmost


def test_status_every_second_with_hardware_id(nodes):
    graph, grounder, probe, client = nodes
    before = probe.counts()
    assert graph.wait_for(lambda: len(probe.new('statuses', before)) >= 2)
    status = probe.new('statuses', before)[-1]
    name = grounder.get_fully_qualified_name()
    assert status.name == f'{name}: status' and status.hardware_id == name
    assert status.level == DiagnosticStatus.OK and status.message == 'active'
    assert {v.key: v.value for v in status.values}['state'] == 'active'


def test_another_entity_table_configures_with_the_default_checkpoint(ros_context):
    graph = ros_context
    node = graph.add(
        GrounderNode(
            context=graph.context,
            namespace=unique_namespace('office'),
            parameter_overrides=[
                Parameter('entity_table', value='entities_office.yaml'),
                Parameter('torch_threads', value=0),
            ],
        )
    )
    assert node.grounder is not None and node.grounder.entities.domain != 'puddleworld'


@pytest.mark.parametrize(
    'instruction, cell',
    [
        ('reach cell two below the sofa', (7, 4)),  # the 2x3 sofa: under its bottom middle
        ('please go two squares south of the couch', (7, 4)),  # an alias, a paraphrase
        ('zorp reach cell two below the sfoa blorf', (7, 4)),  # a typo, unknown words
        ('stop one metre north of the refrigerator', (5, 8)),  # metres at 0.5 m cells
        ('reach the southernmost chair', (7, 1)),  # solid: the free cell beside the chair
    ],
)
def test_the_node_grounds_a_table_of_its_own(ros_context, instruction, cell):
    """Over DDS, with entity_table: entities_office.yaml and the default checkpoint."""
    graph = ros_context
    namespace = unique_namespace('office_words')
    graph.add(
        GrounderNode(
            context=graph.context,
            namespace=namespace,
            parameter_overrides=[
                Parameter('entity_table', value='entities_office.yaml'),
                Parameter('torch_threads', value=0),
            ],
        )
    )
    client = GroundingClient(namespace, context=graph.context, timeout=WAIT)
    try:
        assert client.wait_for_server(), 'no ground_instruction service'
        grid = np.zeros((10, 10), dtype=np.int64)
        grid[0, :] = 1  # wall (the office table's indices)
        grid[4:6, 3:6] = 7  # a sofa over 2x3 cells: rows 4-5, columns 3-5
        grid[7, 8] = 9  # a fridge
        grid[8, 1] = grid[2, 2] = 3  # two chairs
        info = convert.map_info(grid.shape, resolution=0.5, origin=(1.0, -2.0))
        answer = client.ground(
            instruction,
            entity_map=convert.grid_to_occupancy_grid(grid, Header(frame_id='map'), info),
        )
        assert answer.success, answer
        position = answer.goal.pose.position
        assert (position.x, position.y) == pytest.approx(convert.cell_centre(cell, info)[:2])
    finally:
        client.close()
