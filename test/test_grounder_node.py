# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The grounder node over real DDS, against the Python API it adapts.

Every output of a good request matches Grounder.ground on the same grid; every kind of bad input
gets a warning, a WARN diagnostic naming the problem and no goal, and the node answers the next
good request. One node (a seeded untrained model, so no trained checkpoint is needed) for the
module.
"""

import math
import time

import numpy as np
import pytest
import torch

pytest.importorskip('rclpy', reason='rclpy is not installed')

from diagnostic_msgs.msg import DiagnosticStatus  # noqa: E402, I100
from grounder_helpers import (  # noqa: E402
    ANY_CONFIDENCE,
    make_probe,
    PUDDLEWORLD_TABLE,
    random_checkpoint,
    unique_namespace,
)
from rclpy.parameter import Parameter  # noqa: E402
from spatial_grounding_ros.data.generator import generate  # noqa: E402
from spatial_grounding_ros.grounder import Grounder  # noqa: E402
from spatial_grounding_ros.models.protocol import TextVectorCode  # noqa: E402
from spatial_grounding_ros.ros import convert  # noqa: E402
from spatial_grounding_ros.ros.grounder_node import GrounderNode  # noqa: E402
from std_msgs.msg import Header  # noqa: E402

NAMESPACE = unique_namespace('grounder_node_test')
MAX_CELLS = 400
MAX_CHARS = 80
NO_GOAL_WAIT = 0.3  # after the diagnostic, how long a stray goal would have had to arrive
WORLDS = generate(4, seed=3, mode='mixed')


@pytest.fixture(scope='module')
def checkpoint(tmp_path_factory):
    return random_checkpoint(tmp_path_factory.mktemp('ckpt') / 'random.pt')


@pytest.fixture(scope='module')
def reference(checkpoint):
    return Grounder.from_checkpoint(str(checkpoint), min_confidence=0.0)


@pytest.fixture(scope='module')
def nodes(ros_module_context, checkpoint):
    graph = ros_module_context
    grounder = graph.add(
        GrounderNode(
            context=graph.context,
            namespace=NAMESPACE,
            parameter_overrides=[
                Parameter('checkpoint', value=str(checkpoint)),
                PUDDLEWORLD_TABLE,
                ANY_CONFIDENCE,
                Parameter('max_cells', value=MAX_CELLS),
                Parameter('max_instruction_chars', value=MAX_CHARS),
                # leave torch's thread count to the rest of the test session
                Parameter('torch_threads', value=0),
            ],
        )
    )
    probe = graph.add(make_probe(graph.context, NAMESPACE, grounder.get_fully_qualified_name()))
    assert graph.wait_for(probe.connected), 'probe and grounder never matched'
    return graph, grounder, probe


def wait_held(nodes, message) -> None:
    """
    Wait until the grounder says it holds `message` as its map.

    Until the grounder says it holds `message` as its map (its OK entity_map diagnostic
    with that stamp): topics are not ordered among each other, so an instruction sent right
    after a map could otherwise overtake it. The node's own state agrees.
    """
    graph, grounder, probe = nodes
    assert graph.wait_for(lambda: probe.holds(message)), 'no OK diagnostic for the map'
    assert grounder.map_msg.header.stamp == message.header.stamp


def raw_values(msg) -> np.ndarray:
    return convert.float32_multiarray_to_value_map(msg)


def good_request(nodes, reference, world: int = 0, info=None, frame_id='map', grid=None):
    """Publish a world's map and its instruction; check every output against the API."""
    graph, grounder, probe = nodes
    grid = WORLDS.grids[world] if grid is None else grid
    text = WORLDS.instructions[world]
    map_message = probe.publish_map(grid, info, frame_id)
    wait_held(nodes, map_message)
    before = probe.counts()
    probe.publish_instruction(text)
    outputs = ('goals', 'value_maps', 'raw_maps', 'relation_maps', 'diagnostics')
    assert graph.wait_for(lambda: all(probe.new(k, before) for k in outputs)), (
        f'missing outputs for a good request: {probe.counts()} after {before}'
    )
    expected = reference.ground(grid, text)
    info = info or convert.map_info(grid.shape)
    [goal] = probe.new('goals', before)
    assert goal.header.frame_id == frame_id
    # README: the goal (and the maps) carry the entity map's stamp, not the time of grounding
    assert goal.header.stamp == map_message.header.stamp
    assert (goal.pose.position.x, goal.pose.position.y, goal.pose.position.z) == pytest.approx(
        convert.cell_centre(expected.goal, info)
    )
    np.testing.assert_allclose(
        raw_values(probe.new('raw_maps', before)[-1]), expected.values, rtol=1e-6, atol=1e-6
    )
    [value_map] = probe.new('value_maps', before)
    assert value_map.header.stamp == map_message.header.stamp
    assert (value_map.info.width, value_map.info.height) == (grid.shape[1], grid.shape[0])
    assert value_map.info.resolution == info.resolution
    assert value_map.header.frame_id == frame_id
    assert min(value_map.data) == 0 and max(value_map.data) == 100
    # the best cell is 100 in the scaled map, at the OccupancyGrid index of the goal
    row, col = expected.goal
    assert value_map.data[(grid.shape[0] - 1 - row) * grid.shape[1] + col] == 100
    relation = probe.new('relation_maps', before)[-1].data
    assert 0 <= min(relation) and max(relation) == 100
    [status] = probe.new('diagnostics', before)
    # a goal less than even odds to be the cell meant is WARN (the random model's usually are)
    sure = DiagnosticStatus.OK if expected.confidence >= 0.5 else DiagnosticStatus.WARN
    assert status.level == sure and f'{expected.goal}' in status.message
    values = {v.key: v.value for v in status.values}
    assert values['intent'] == 'go' and values['confidence'] == f'{expected.confidence:.3f}'
    return goal


def expect_rejected(nodes, before: dict, problem: str):
    """Since `before`: one WARN diagnostic naming `problem`, a warning saying it, no goal."""
    graph, grounder, probe = nodes
    assert graph.wait_for(lambda: probe.new('diagnostics', before)), (
        f'no diagnostic for bad input ({problem!r})'
    )
    [status] = probe.new('diagnostics', before)
    assert status.level == DiagnosticStatus.WARN and problem in status.message, status
    assert graph.wait_for(lambda: any(problem in w for w in probe.new('warnings', before)))
    time.sleep(NO_GOAL_WAIT)
    assert not probe.new('goals', before), 'a goal was published for bad input'


def test_good_request_matches_the_python_api(nodes, reference):
    good_request(nodes, reference, world=0)
    good_request(
        nodes,
        reference,
        world=1,
        frame_id='odom',
        info=convert.map_info((10, 10), resolution=0.25, origin=(-3.0, 4.0), yaw=0.4),
    )


@pytest.mark.parametrize(
    'orientation',
    [
        (0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4)),  # +90 degrees about z
        (0.0, 0.0, math.sin(-1.25), math.cos(-1.25)),  # -2.5 rad about z
        (0.0, 0.0, 1.2, 1.6),  # a yaw, not normalised (the node normalises an origin)
        (math.sin(0.15), 0.0, 0.0, math.cos(0.15)),  # tilted: 0.3 rad about x
    ],
    ids=['yaw-90', 'yaw-minus-2.5', 'not-normalised', 'tilted'],
)
def test_goal_orientation_is_the_identity_on_a_rotated_origin(nodes, reference, orientation):
    """
    Check docs/ros.md: goal_heading `identity` faces the map frame's +x.

    The default, `auto`, is the identity here: no goal on a PuddleWorld map stands beside a
    solid landmark.

    "(also when the grid's origin is rotated): an instruction names a place, not a heading".
    The goal is where the rotated grid puts the cell (good_request checks the position against
    the API), and its orientation is exactly the identity quaternion, not the origin's.
    """
    graph, grounder, probe = nodes
    assert grounder.get_parameter('goal_heading').value == 'auto'  # the default
    info = convert.map_info((10, 10), resolution=0.5, origin=(2.0, -1.0))
    o = info.origin.orientation
    o.x, o.y, o.z, o.w = orientation
    goal = good_request(nodes, reference, world=1, info=info)
    q = goal.pose.orientation
    assert (q.x, q.y, q.z, q.w) == (0.0, 0.0, 0.0, 1.0)


def bad_map(grid=None, **change):
    msg = convert.grid_to_occupancy_grid(
        WORLDS.grids[0] if grid is None else grid, Header(frame_id='map')
    )
    for key, value in change.items():
        setattr(msg.info, key, value)
    return msg


def short_data():
    msg = bad_map()
    msg.data = msg.data[:-1]
    return msg


@pytest.mark.parametrize(
    'make, problem',
    [
        (short_data, 'map data has 99 values, but width x height = 10x10 = 100'),
        (lambda: bad_map(width=0), 'width and height must be positive'),
        (lambda: bad_map(height=0), 'width and height must be positive'),
        (lambda: bad_map(np.zeros((20, 21), int)), f'more than max_cells={MAX_CELLS}'),
        (lambda: bad_map(np.full((3, 3), 12)), 'entity values [12] outside the puddleworld table'),
        (lambda: bad_map(np.full((3, 3), -1)), 'entity values [-1] outside the puddleworld table'),
        (lambda: bad_map(resolution=float('nan')), 'resolution nan must be a positive'),
        (lambda: bad_map(resolution=0.0), 'resolution 0.0 must be a positive'),
        (lambda: bad_map(resolution=-0.5), 'resolution -0.5 must be a positive'),
    ],
    ids=[
        'data-length',
        'width-0',
        'height-0',
        'too-many-cells',
        'entity-12',
        'entity-minus-1',
        'resolution-nan',
        'resolution-0',
        'resolution-negative',
    ],
)
def test_bad_map_is_rejected_and_the_node_recovers(nodes, reference, make, problem):
    graph, grounder, probe = nodes
    before = probe.counts()
    probe.publish_map(message=make())
    expect_rejected(nodes, before, problem)
    assert grounder.grid is None  # the last map was bad: no stale map to ground on
    good_request(nodes, reference, world=2)


@pytest.mark.parametrize(
    'text, problem',
    [
        ('', 'instruction is empty'),
        (' \t\n ', 'instruction is empty'),
        ('reach cell ' * 10, f'more than max_instruction_chars={MAX_CHARS}'),
        (
            'xyzzy plugh frobozz',
            "no word of the instruction 'xyzzy plugh frobozz' is in the vocab",
        ),
        ('?!...', 'instruction has no words'),
    ],
    ids=['empty', 'whitespace', 'too-long', 'unknown-words', 'no-words'],
)
def test_bad_instruction_is_rejected_and_the_node_recovers(nodes, reference, text, problem):
    graph, grounder, probe = nodes
    good_request(nodes, reference, world=0)  # a map is held: the rejection is the text's
    before = probe.counts()
    probe.publish_instruction(text)
    expect_rejected(nodes, before, problem)
    good_request(nodes, reference, world=3)


def test_instruction_without_a_map_is_held_until_one_arrives(nodes, reference):
    graph, grounder, probe = nodes
    before = probe.counts()
    probe.publish_map(message=bad_map(resolution=0.0))  # whatever came before: no map now
    expect_rejected(nodes, before, 'resolution 0.0')
    text = WORLDS.instructions[1]
    before = probe.counts()
    probe.publish_instruction(text)
    expect_rejected(nodes, before, 'no valid entity_map held yet: holding instruction')
    before = probe.counts()
    probe.publish_map(WORLDS.grids[1])
    assert graph.wait_for(lambda: probe.new('goals', before)), 'held instruction never grounded'
    expected = reference.ground(WORLDS.grids[1], text)
    position = probe.goals[-1].pose.position
    assert (position.x, position.y) == pytest.approx(
        convert.cell_centre(expected.goal, convert.map_info((10, 10)))[:2]
    )


def test_map_of_another_size_is_a_new_map(nodes, reference):
    good_request(nodes, reference, world=0)
    # a crop that keeps world 1's star: a map that lost its referent is declined instead
    good_request(nodes, reference, world=1, grid=WORLDS.grids[1][:7, :9].copy())
    good_request(nodes, reference, world=3)


def test_reground_on_map_change(nodes, reference):
    graph, grounder, probe = nodes
    good_request(nodes, reference, world=0)
    before = probe.counts()
    # off (the default): a new map waits for the next instruction
    wait_held(nodes, probe.publish_map(WORLDS.grids[3]))
    time.sleep(NO_GOAL_WAIT)
    assert not probe.new('goals', before)
    grounder.set_parameters([Parameter('reground_on_map_change', value=True)])
    try:
        probe.publish_map(WORLDS.grids[1])
        assert graph.wait_for(lambda: probe.new('goals', before)), 'no goal for the new map'
        expected = reference.ground(WORLDS.grids[1], WORLDS.instructions[0])
        position = probe.goals[-1].pose.position
        assert (position.x, position.y) == pytest.approx(
            convert.cell_centre(expected.goal, convert.map_info((10, 10)))[:2]
        )
    finally:
        grounder.set_parameters([Parameter('reground_on_map_change', value=False)])


def test_a_rejected_instruction_drops_the_held_one(nodes, reference):
    """
    README: "a rejected instruction drops the held instruction".

    With reground_on_map_change, a held instruction is grounded again on each new map; after a
    rejected instruction the next map gets no goal. Likewise an instruction waiting for a map is
    dropped by a rejected one and never grounded.
    """
    graph, grounder, probe = nodes
    good_request(nodes, reference, world=0)
    grounder.set_parameters([Parameter('reground_on_map_change', value=True)])
    try:
        before = probe.counts()
        probe.publish_map(WORLDS.grids[1])  # the control: the held instruction is re-grounded
        assert graph.wait_for(
            lambda: (
                probe.new('goals', before)
                and any(s.name.endswith(': grounding') for s in probe.new('diagnostics', before))
            )
        ), 'held instruction not re-grounded'
        before = probe.counts()
        probe.publish_instruction('xyzzy plugh frobozz')
        expect_rejected(nodes, before, 'no word of the instruction')
        before = probe.counts()
        wait_held(nodes, probe.publish_map(WORLDS.grids[2]))
        time.sleep(NO_GOAL_WAIT)
        assert not probe.new('goals', before), 'a rejected instruction left the old one held'
    finally:
        grounder.set_parameters([Parameter('reground_on_map_change', value=False)])
    # waiting for a map: held (WARN "holding"), then dropped by a rejected one
    before = probe.counts()
    probe.publish_map(message=bad_map(resolution=0.0))
    expect_rejected(nodes, before, 'resolution 0.0')
    before = probe.counts()
    probe.publish_instruction(WORLDS.instructions[1])
    expect_rejected(nodes, before, 'holding instruction')
    before = probe.counts()
    probe.publish_instruction(' ')
    expect_rejected(nodes, before, 'instruction is empty')
    before = probe.counts()
    wait_held(nodes, probe.publish_map(WORLDS.grids[1]))
    time.sleep(NO_GOAL_WAIT)
    assert not probe.new('goals', before), 'the dropped instruction was grounded'
    good_request(nodes, reference, world=3)


def test_empty_frame_id_takes_default_frame_id(nodes, reference):
    """
    Check a claim of the README.

    README: `default_frame_id` (default `map`) is the outputs' frame when the entity map's frame_id
    is empty; a non-empty frame is passed through (good_request's "odom").
    """
    graph, grounder, probe = nodes
    assert grounder.get_parameter('default_frame_id').value == 'map'
    try:
        for default in ('map', 'robot1/map'):
            grounder.set_parameters([Parameter('default_frame_id', value=default)])
            wait_held(nodes, probe.publish_map(WORLDS.grids[0], frame_id=''))
            before = probe.counts()
            probe.publish_instruction(WORLDS.instructions[0])
            outputs = ('goals', 'value_maps', 'relation_maps')
            assert graph.wait_for(lambda: all(probe.new(k, before) for k in outputs))
            for k in outputs:
                assert probe.new(k, before)[-1].header.frame_id == default, (k, default)
    finally:
        grounder.set_parameters([Parameter('default_frame_id', value='map')])


def test_cost_encoding_puts_the_goal_cell_at_0(nodes, reference):
    """
    Check `ros2 param set ... value_map_encoding cost`.

    The next value_map has the goal cell at 0 and the worst cell at 100, each cell 100 minus its
    display value; `display` again restores the best = 100 scale.
    """
    graph, grounder, probe = nodes
    good_request(nodes, reference, world=1)  # display: best = 100 (checked there)
    shown = probe.value_maps[-1].data
    try:
        result = grounder.set_parameters([Parameter('value_map_encoding', value='cost')])
        assert result[0].successful
        wait_held(nodes, probe.publish_map(WORLDS.grids[1]))
        before = probe.counts()
        probe.publish_instruction(WORLDS.instructions[1])
        assert graph.wait_for(lambda: probe.new('value_maps', before))
        [cost] = probe.new('value_maps', before)
        row, col = reference.ground(WORLDS.grids[1], WORLDS.instructions[1]).goal
        assert cost.data[(10 - 1 - row) * 10 + col] == 0 and max(cost.data) == 100
        assert [c + d for c, d in zip(cost.data, shown)] == [100] * 100
    finally:
        grounder.set_parameters([Parameter('value_map_encoding', value='display')])
    good_request(nodes, reference, world=1)


class FailingModel(torch.nn.Module):
    """
    A model whose grounding raises as torch does when memory runs out.

    A real request on a huge map can; this one does it on demand.
    """

    def text_code(self, tokens):
        return TextVectorCode(text=torch.zeros(1, 7))

    def ground(self, grids, code, return_aux=False):
        raise RuntimeError(
            'DefaultCPUAllocator: not enough memory: you tried to allocate 412316860416 bytes.'
        )


def test_a_failing_model_is_an_error_diagnostic_and_the_node_keeps_running(nodes, reference):
    """
    Check a claim of the README.

    README: "ERROR if the model fails": an exception in the model's forward is an ERROR diagnostic
    and an error log line naming it, no goal, and the next request is answered.
    """
    graph, grounder, probe = nodes
    wait_held(nodes, probe.publish_map(WORLDS.grids[0]))
    model = grounder.grounder.model
    grounder.grounder.model = FailingModel()
    try:
        before = probe.counts()
        probe.publish_instruction(WORLDS.instructions[0])
        assert graph.wait_for(lambda: probe.new('diagnostics', before))
        [status] = probe.new('diagnostics', before)
        assert status.level == DiagnosticStatus.ERROR and status.name.endswith(': grounding')
        assert 'failed: RuntimeError: DefaultCPUAllocator: not enough memory' in status.message
        assert graph.wait_for(
            lambda: any('DefaultCPUAllocator' in w for w in probe.new('warnings', before))
        )
        time.sleep(NO_GOAL_WAIT)
        assert not probe.new('goals', before)
    finally:
        grounder.grounder.model = model
        grounder.grounder.text_codes.clear()  # the failing model's code of the instruction
    # the failed instruction was reported, not kept waiting: the next map does not ground it
    assert not grounder.hold.pending
    wait_held(nodes, probe.publish_map(WORLDS.grids[1]))
    good_request(nodes, reference, world=1)


def test_a_late_subscriber_gets_the_latest_value_maps(ros_context, checkpoint, reference):
    """
    value_map and value_map_raw are latched: built on demand, yet a late subscriber has them.

    With no one subscribed the grounder keeps a grounding's maps unbuilt (LatchedOutput); a
    subscriber that comes later gets the latest grounding's, one that is there gets each.
    """
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import OccupancyGrid
    from rclpy.node import Node
    from spatial_grounding_ros.ros.qos import LATCHED
    from std_msgs.msg import Float32MultiArray, String

    graph, namespace = ros_context, unique_namespace('late_subscriber_test')
    overrides = [Parameter('checkpoint', value=str(checkpoint)), PUDDLEWORLD_TABLE, ANY_CONFIDENCE]
    grounder = graph.add(
        GrounderNode(context=graph.context, namespace=namespace, parameter_overrides=overrides)
    )
    client = graph.add(Node('late_client', namespace=namespace, context=graph.context))
    goals = []
    goal_sub = client.create_subscription(PoseStamped, 'goal_pose', goals.append, 10)
    map_pub = client.create_publisher(OccupancyGrid, 'entity_map', LATCHED)
    instruction_pub = client.create_publisher(String, 'instruction', 10)
    assert graph.wait_for(lambda: instruction_pub.get_subscription_count() > 0
                          and goal_sub.get_publisher_count() > 0)
    grid = WORLDS.grids[1]
    map_pub.publish(convert.grid_to_occupancy_grid(grid, Header(frame_id='map')))
    assert graph.wait_for(lambda: grounder.grid is not None)

    def ground(world: int) -> np.ndarray:
        count = len(goals)
        instruction_pub.publish(String(data=WORLDS.instructions[world]))
        assert graph.wait_for(lambda: len(goals) > count), 'no goal'
        return reference.ground(grid, WORLDS.instructions[world]).values

    def subscribe() -> tuple[Node, list, list]:
        node = Node('late_subscriber', namespace=namespace, context=graph.context)
        raws, maps = [], []
        node.create_subscription(Float32MultiArray, 'value_map_raw', raws.append, LATCHED)
        node.create_subscription(OccupancyGrid, 'value_map', maps.append, LATCHED)
        return graph.add(node), raws, maps

    ground(0)
    expected = ground(2)  # the latest, nobody subscribed to its maps
    late, raws, maps = subscribe()
    assert graph.wait_for(lambda: raws and maps), 'a late subscriber got no value map'
    np.testing.assert_allclose(raw_values(raws[-1]), expected, rtol=1e-6, atol=1e-6)
    assert (maps[-1].info.width, maps[-1].info.height) == (grid.shape[1], grid.shape[0])
    expected = ground(3)  # subscribed: at once
    assert graph.wait_for(lambda: len(raws) == 2 and len(maps) == 2)
    np.testing.assert_allclose(raw_values(raws[-1]), expected, rtol=1e-6, atol=1e-6)
    graph.executor.remove_node(late)
    late.destroy_node()
    expected = ground(0)
    _, raws, _ = subscribe()  # a second late subscriber: the latest again
    assert graph.wait_for(lambda: raws), 'a second late subscriber got no value map'
    np.testing.assert_allclose(raw_values(raws[-1]), expected, rtol=1e-6, atol=1e-6)
