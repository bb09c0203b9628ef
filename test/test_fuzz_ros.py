# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Fuzz of the nodes' new surfaces over real DDS: seeded, bounded, a few seconds each.

The ground_instruction service gets malformed requests (odd text, maps of wrong length, size,
values, resolution or origin) and the entity mapper malformed markers and maps. Every request
is answered (success, or a reason), no input is an ERROR (an error nobody expected), and the
next good input works. The test_grounder_node bad-input cases are the hand-picked ones; these
are drawn at random around them.
"""

from __future__ import annotations

import secrets

import numpy as np
import pytest

pytest.importorskip('rclpy', reason='rclpy is not installed')
pytest.importorskip('spatial_grounding_interfaces', reason='make setup builds the interfaces')

from conftest import WAIT  # noqa: E402, I100
from grounder_helpers import unique_namespace  # noqa: E402
import test_entity_mapper as office  # noqa: E402

SPECIALS = [float('nan'), float('inf'), -float('inf'), 1e300, -1e300, 0.0, -1.0, 1e-300]
WORDS = 'reach go the cell two below above left of fridge sofa desk chair metres north 3 é 🙂'


def number(rng):
    return float(rng.choice(SPECIALS)) if rng.random() < 0.4 else float(rng.normal(0, 50))


def text(rng):
    kind = rng.integers(5)
    if kind == 0:
        return ''.join(chr(int(c)) for c in rng.integers(1, 0x2FFF, rng.integers(0, 40)))
    if kind == 1:
        return 'reach ' * int(rng.integers(0, 200))
    words = WORDS.split()
    return ' '.join(rng.choice(words, rng.integers(0, 12)))


def random_map(rng):
    """Return an OccupancyGrid, often malformed: size, data length, values, resolution, origin."""
    from spatial_grounding_ros.ros import convert
    from std_msgs.msg import Header

    h, w = (int(v) for v in rng.integers(1, 16, 2))
    grid = rng.integers(-5, 40, (h, w))
    msg = convert.grid_to_occupancy_grid(
        np.clip(grid, -128, 127), Header(frame_id='map'), convert.map_info((h, w), 0.25)
    )
    fault = rng.integers(7)
    if fault == 0:
        msg.data = msg.data[: int(rng.integers(0, len(msg.data)))]
    elif fault == 1:
        msg.info.width, msg.info.height = (int(v) for v in rng.integers(0, 3000, 2))
    elif fault == 2:
        msg.info.resolution = number(rng)
    elif fault == 3:
        p = msg.info.origin.position
        p.x, p.y, p.z = number(rng), number(rng), number(rng)
    elif fault == 4:
        q = msg.info.origin.orientation
        q.x, q.y, q.z, q.w = (number(rng) for _ in range(4))
    return msg


def test_fuzz_the_ground_instruction_service(ros_context):
    from diagnostic_msgs.msg import DiagnosticStatus
    from rclpy.node import Node
    from rclpy.parameter import Parameter
    from spatial_grounding_interfaces.srv import GroundInstruction
    from spatial_grounding_ros.ros import convert
    from spatial_grounding_ros.ros.grounder_node import GrounderNode
    from spatial_grounding_ros.ros.qos import BURST
    from std_msgs.msg import Header

    graph = ros_context
    namespace = unique_namespace('fuzz_service')
    node = graph.add(
        GrounderNode(
            context=graph.context,
            namespace=namespace,
            parameter_overrides=[Parameter('torch_threads', value=0)],
        )
    )
    errors = []  # the node's ERROR diagnostics: an error nobody expected
    report = node.report

    def recording(part, level, message, **values):
        if level == DiagnosticStatus.ERROR:
            errors.append(message)
        report(part, level, message, **values)

    node.report = recording
    client_node = graph.add(Node('fuzz_client', namespace=namespace, context=graph.context))

    client = client_node.create_client(GroundInstruction, 'ground_instruction', qos_profile=BURST)
    assert client.wait_for_service(timeout_sec=WAIT)
    rng = np.random.default_rng(42)
    requests = []
    for _ in range(60):
        request = GroundInstruction.Request(instruction=text(rng))
        if rng.random() < 0.8:
            request.entity_map = random_map(rng)
        requests.append(request)
    futures = [client.call_async(r) for r in requests]
    assert graph.wait_for(lambda: all(f.done() for f in futures)), 'a request was never answered'
    for request, future in zip(requests, futures):
        answer = future.result()
        assert answer.success or answer.reason, request.instruction
    assert not errors, errors
    good = GroundInstruction.Request(instruction='reach the cell two below the fridge')
    grid = np.zeros((8, 8), np.int64)
    grid[1, 4] = office.FRIDGE
    good.entity_map = convert.grid_to_occupancy_grid(grid, Header(frame_id='map'))
    future = client.call_async(good)
    assert graph.wait_for(future.done)
    assert future.result().success, future.result().reason


def random_marker(rng):
    from visualization_msgs.msg import Marker

    m = Marker(ns=str(rng.choice(['landmarks', '', 'x' * 300])), id=int(rng.integers(-5, 5)))
    types = [Marker.CUBE, Marker.CYLINDER, Marker.TEXT_VIEW_FACING, Marker.ARROW]
    m.type = int(rng.choice(types))
    m.action = int(rng.choice([Marker.ADD, Marker.ADD, Marker.ADD, Marker.DELETE, 3, 7]))
    m.text = text(rng) if rng.random() < 0.5 else str(rng.choice(['fridge', 'desk', 'chairs']))
    m.header.frame_id = str(rng.choice(['map', '', 'odom']))
    p, q = m.pose.position, m.pose.orientation
    p.x, p.y, p.z = number(rng), number(rng), number(rng)
    q.w = 1.0 if rng.random() < 0.7 else number(rng)
    m.scale.x, m.scale.y = number(rng), number(rng)
    return m


def test_fuzz_the_entity_mapper(ros_context):
    from diagnostic_msgs.msg import DiagnosticStatus
    from visualization_msgs.msg import Marker, MarkerArray

    graph = ros_context
    namespace = '/fuzz_mapper_' + secrets.token_hex(3)
    office.mapper(graph, namespace)
    probe = graph.add(office.make_probe(graph.context, namespace))
    assert graph.wait_for(
        lambda: probe.landmarks_pub.get_subscription_count() > 0
        and probe.map_pub.get_subscription_count() > 0
        and probe.hears_diagnostics()
    )
    probe.map_pub.publish(office.slam_message())
    assert graph.wait_for(lambda: probe.grid() is not None)
    rng = np.random.default_rng(7)
    for round_ in range(30):
        if round_ % 3 == 0:
            probe.map_pub.publish(random_map(rng))
        probe.landmarks_pub.publish(
            MarkerArray(markers=[random_marker(rng) for _ in range(int(rng.integers(0, 8)))])
        )
    # a good map and markers afterwards give the expected entity map
    probe.map_pub.publish(office.slam_message(stamp=99))
    probe.landmarks_pub.publish(MarkerArray(markers=[office.markers().markers[0]]))
    probe.landmarks_pub.publish(MarkerArray(markers=[Marker(action=Marker.DELETEALL)]))
    probe.landmarks_pub.publish(office.markers())
    assert graph.wait_for(lambda: np.array_equal(probe.grid(), office.EXPECTED)), probe.grid()
    errors = [s.message for s in probe.diagnostics if s.level == DiagnosticStatus.ERROR]
    assert not errors, errors
