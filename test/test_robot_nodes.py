# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The nodes as a robot runs them (issue 42): real processes over DDS, started with no parameters.

The entity mapper and the grounder, each its console script with nothing but a namespace, work
together on an office SLAM map with landmark markers; the grounder answers 200 concurrent
service calls (or refuses them as busy), accounts for each of a burst of 50 instructions, and
keeps its 1 Hz status while a 1024x1024 map grounds; the mapper outlives bad markers (a latched
one too) and a map past max_cells, under 1 GB; a client learns that its call was lost when the
server goes away.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
import subprocess
import time

import numpy as np
import pytest

pytest.importorskip('rclpy', reason='rclpy is not installed')
pytest.importorskip('spatial_grounding_interfaces', reason='make setup builds the interfaces')

from conftest import WAIT  # noqa: E402, I100
from grounder_helpers import interrupt, unique_namespace  # noqa: E402
from spatial_grounding_ros.ros.grounder_node import INLINE_CELLS  # noqa: E402
from spatial_grounding_ros.ros.processes import executable  # noqa: E402
import test_entity_mapper as office  # noqa: E402

STATUS_GAP = 1.6  # seconds: the 1 Hz status may come late, never stop


def start(name: str, namespace: str, log: Path, *parameters: str) -> subprocess.Popen:
    """Start a node's console script in `namespace`, with only the `parameters` given."""
    extra = [a for p in parameters for a in ('-p', p)]
    return subprocess.Popen(
        [*executable(name), '--ros-args', '-r', f'__ns:={namespace}', *extra],
        stdout=log.open('w'),
        stderr=subprocess.STDOUT,
        env={**os.environ, 'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST'},
    )


def peak_rss_mb(process: subprocess.Popen) -> float:
    for line in Path(f'/proc/{process.pid}/status').read_text().splitlines():
        if line.startswith('VmHWM:'):
            return int(line.split()[1]) / 1024
    raise AssertionError('no VmHWM')


def make_probe(context, namespace):
    """Return the mapper test's probe, timing the grounder's status, with deep publishers."""
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from spatial_grounding_interfaces.srv import GroundInstruction
    from spatial_grounding_ros.ros.qos import BURST, LATCHED
    from std_msgs.msg import String
    from nav_msgs.msg import OccupancyGrid

    probe = office.make_probe(context, namespace)
    probe.status_times = []  # (time.monotonic(), status) of the grounder's 1 Hz status
    grounder_status = f'{namespace}/spatial_grounder: status'
    plain = probe.on_diagnostics

    def on_diagnostics(msg):
        now = time.monotonic()
        probe.status_times += [(now, s) for s in msg.status if s.name == grounder_status]
        plain(msg)

    probe.on_diagnostics = on_diagnostics
    probe.destroy_subscription(probe.diagnostics_sub)
    from diagnostic_msgs.msg import DiagnosticArray

    probe.diagnostics_sub = probe.create_subscription(
        DiagnosticArray, '/diagnostics', on_diagnostics, QoSProfile(
            depth=1000, reliability=ReliabilityPolicy.RELIABLE
        )
    )
    probe.burst_pub = probe.create_publisher(String, 'instruction', BURST)
    probe.entity_pub = probe.create_publisher(OccupancyGrid, 'entity_map', LATCHED)
    probe.client = probe.create_client(GroundInstruction, 'ground_instruction', qos_profile=BURST)
    return probe


@pytest.fixture(scope='module')
def robot(ros_module_context, tmp_path_factory):
    """Start the mapper and the grounder as processes with no parameters, and a probe."""
    graph = ros_module_context
    namespace = unique_namespace('robot')
    logs = tmp_path_factory.mktemp('robot')
    processes = [
        start('entity_mapper', namespace, logs / 'mapper.log'),
        start('grounder', namespace, logs / 'grounder.log'),
    ]
    probe = graph.add(make_probe(graph.context, namespace))
    try:
        assert graph.wait_for(
            lambda: probe.landmarks_pub.get_subscription_count() > 0
            and probe.map_pub.get_subscription_count() > 0
            and probe.burst_pub.get_subscription_count() > 0
            and probe.goal_sub.get_publisher_count() > 0
            and probe.entity_sub.get_publisher_count() > 0
            and probe.client.service_is_ready()
            and probe.hears_diagnostics(nodes=2)
            and probe.status_times,
        ), [p.poll() for p in processes]
        yield graph, namespace, probe, processes
    finally:
        for p in processes:
            code, _ = interrupt(p)
        print({name: (logs / name).read_text()[-2000:] for name in ('mapper.log', 'grounder.log')})


def grounder_said(probe, namespace, part, needle=''):
    return [
        s
        for s in probe.diagnostics
        if s.name == f'{namespace}/spatial_grounder: {part}' and needle in s.message
    ]


def hold_entity_map(graph, probe, namespace, grid, resolution=0.25):
    """Publish an office entity map (data-set order) straight to the grounder; wait until held."""
    from spatial_grounding_ros.ros import convert
    from std_msgs.msg import Header

    msg = convert.grid_to_occupancy_grid(
        grid, Header(frame_id='map'), convert.map_info(grid.shape, resolution)
    )
    msg.header.stamp.sec = int(time.time()) % 100000
    msg.header.stamp.nanosec = time.time_ns() % 10**9
    probe.entity_pub.publish(msg)
    probe.entity_maps.append(msg)  # office.held() reads the latest entity map's stamp
    assert graph.wait_for(lambda: office.held(probe, namespace)), 'the map was never held'
    return msg


def office_grid(size=10):
    grid = np.zeros((size, size), dtype=np.int64)  # floor
    grid[2, 5] = office.FRIDGE
    return grid


def test_mapper_and_grounder_with_no_parameters_give_goals(robot):
    """An office SLAM map and markers -> entity_map -> goal_pose, both nodes on their defaults."""
    from std_msgs.msg import String

    graph, namespace, probe, _ = robot
    probe.map_pub.publish(office.slam_message())
    probe.landmarks_pub.publish(office.markers())
    assert graph.wait_for(
        lambda: probe.grid() is not None
        and np.array_equal(probe.grid(), office.EXPECTED)
        and office.held(probe, namespace)
    ), probe.grid()
    for text, cell in {
        'go half a metre north of the fridge': (2, 2),
        'go one metre east of the printer': (4, 9),
    }.items():
        before = len(probe.goals)
        probe.instruction_pub.publish(String(data=text))
        assert graph.wait_for(lambda: len(probe.goals) > before), grounder_said(
            probe, namespace, 'grounding'
        )[-1:]
        p = probe.goals[-1].pose.position
        x, y = office.centre_of(cell)
        assert math.hypot(p.x - x, p.y - y) <= office.CELL / 2, (text, p.x, p.y, x, y)
        assert graph.wait_for(lambda: grounder_said(probe, namespace, 'grounding', repr(text)))
        [status] = grounder_said(probe, namespace, 'grounding', repr(text))
        assert {v.key: v.value for v in status.values}['intent'] == 'go'
    # a solid landmark is approached: a free cell beside its footprint, facing it
    for text, kind in (('go to the fridge', office.FRIDGE), ('go next to the desk', office.DESK)):
        before = len(probe.goals)
        probe.instruction_pub.publish(String(data=text))
        assert graph.wait_for(lambda: len(probe.goals) > before), grounder_said(
            probe, namespace, 'grounding'
        )[-1:]
        pose = probe.goals[-1].pose
        footprint = [office.centre_of(tuple(c)) for c in np.argwhere(office.EXPECTED == kind)]
        here = (pose.position.x, pose.position.y)
        x, y = min(footprint, key=lambda f: math.dist(f, here))
        assert 0 < math.hypot(x - pose.position.x, y - pose.position.y) <= 0.6, text
        q = pose.orientation
        yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
        toward = math.atan2(y - pose.position.y, x - pose.position.x)
        assert abs(math.remainder(yaw - toward, 2 * math.pi)) <= 0.35, (text, yaw, toward)


def test_200_concurrent_service_calls_are_each_answered_or_refused(robot):
    from spatial_grounding_interfaces.srv import GroundInstruction
    from spatial_grounding_ros.ros import convert
    from std_msgs.msg import Header

    graph, namespace, probe, _ = robot
    request = GroundInstruction.Request(
        instruction='reach the cell two below the fridge',
        entity_map=convert.grid_to_occupancy_grid(office_grid(), Header(frame_id='map')),
    )
    futures = [probe.client.call_async(request) for _ in range(200)]
    assert graph.wait_for(lambda: all(f.done() for f in futures), timeout=60.0), (
        f'{sum(not f.done() for f in futures)} of 200 calls never answered'
    )
    answers = [f.result() for f in futures]
    answered = [a for a in answers if a.success]
    refused = [a for a in answers if not a.success]
    assert all(a.reason.startswith('busy: ') for a in refused), {a.reason for a in refused}
    assert answered and len(answered) + len(refused) == 200
    print(f'200 calls: {len(answered)} answered, {len(refused)} refused busy')
    assert all(a.goal.header.frame_id == 'map' and a.intent == 'go' for a in answered)


@pytest.mark.parametrize('size', [10, 256])
def test_each_of_a_burst_of_50_instructions_is_grounded_or_reported_dropped(robot, size):
    """A small map's groundings run as each instruction comes; a large map's take the latest."""
    from std_msgs.msg import String

    graph, namespace, probe, _ = robot
    hold_entity_map(graph, probe, namespace, office_grid(size))
    texts = [f'reach the cell two below the fridge now{i}at{size}' for i in range(50)]
    for text in texts:
        probe.burst_pub.publish(String(data=text))

    def accounted() -> set[str]:
        seen = set()
        for s in probe.diagnostics:
            values = {v.key: v.value for v in s.values}
            if s.name.endswith(': instruction') and 'dropped' in values:
                seen.add(values['dropped'])
            elif s.name.endswith(': grounding'):
                seen |= {t for t in texts if repr(t) in s.message}
        return seen

    assert graph.wait_for(lambda: accounted() >= set(texts)), set(texts) - accounted()
    grounded = [t for t in texts if grounder_said(probe, namespace, 'grounding', repr(t))]
    assert texts[-1] in grounded  # the latest is never dropped
    if size * size <= INLINE_CELLS:  # grounded in the spinning thread, one callback at a time
        assert grounded == texts
    print(f'burst of 50 at {size}x{size}: {len(grounded)} grounded, {50 - len(grounded)} dropped')


def test_status_keeps_ticking_while_a_1024x1024_map_grounds(robot):
    from std_msgs.msg import String

    graph, namespace, probe, _ = robot
    grid = office_grid(1024)
    hold_entity_map(graph, probe, namespace, grid, resolution=0.05)
    text = 'reach the cell two below the fridge'
    start_time = time.monotonic()
    before = len(grounder_said(probe, namespace, 'grounding', repr(text)))
    probe.burst_pub.publish(String(data=text))
    assert graph.wait_for(
        lambda: len(grounder_said(probe, namespace, 'grounding', repr(text))) > before
    )
    end_time = time.monotonic()
    # one more status after the grounding: the gap across its end counts too
    assert graph.wait_for(lambda: probe.status_times[-1][0] > end_time)
    times = [t for t, _ in probe.status_times if t >= start_time - STATUS_GAP]
    gaps = np.diff(times)
    assert len(times) >= 2 and gaps.max() < STATUS_GAP, (gaps.tolist(), end_time - start_time)
    print(f'1024x1024: grounded in {end_time - start_time:.2f} s, status gaps {gaps.round(2)}')


def test_the_mapper_outlives_bad_markers_and_huge_maps(ros_context, tmp_path):
    """
    NaN, inf and huge markers, one latched before the mapper starts, and a map past max_cells.

    The mapper (a process, landmarks transient local so it gets the latched marker at start)
    skips each bad marker with a WARN naming it, refuses the map, stays up under 1 GB, and the
    next good input works.
    """
    from diagnostic_msgs.msg import DiagnosticStatus
    from nav_msgs.msg import OccupancyGrid
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from spatial_grounding_ros.ros import convert
    from std_msgs.msg import Header
    from visualization_msgs.msg import MarkerArray

    graph = ros_context
    namespace = unique_namespace('mapper_robust')
    probe = graph.add(make_probe(graph.context, namespace))
    latched = QoSProfile(
        depth=1,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL,
    )
    latched_pub = probe.create_publisher(MarkerArray, 'landmarks', latched)
    bad = office.markers()
    bad.markers[0].pose.position.x = float('nan')
    latched_pub.publish(bad)  # waits there for the mapper, and for every restart of it
    log = tmp_path / 'mapper.log'
    process = start('entity_mapper', namespace, log, 'landmarks_durability:=transient_local')
    try:
        assert graph.wait_for(
            lambda: probe.map_pub.get_subscription_count() > 0 and probe.hears_diagnostics()
        )
        probe.map_pub.publish(office.slam_message())
        warn = DiagnosticStatus.WARN
        # the one-shot WARN may go out before /diagnostics matched; the 1 Hz status keeps it
        assert graph.wait_for(lambda: probe.said('status', warn, "marker 'landmarks'/0"))
        # the other markers still count: all but the desk
        assert graph.wait_for(
            lambda: probe.grid() is not None and (probe.grid() == office.FRIDGE).sum() == 1
        )
        assert (probe.grid() == office.DESK).sum() == 0
        for change in (
            lambda m: setattr(m.pose.position, 'y', float('inf')),
            lambda m: setattr(m.scale, 'x', float('inf')),
            lambda m: setattr(m.scale, 'y', 1e9),
            lambda m: setattr(m.pose.orientation, 'w', float('nan')),
        ):
            markers = office.markers()
            change(markers.markers[2])
            before = len(probe.diagnostics)
            latched_pub.publish(markers)
            assert graph.wait_for(
                lambda: any(
                    "marker 'landmarks'/2" in s.message and s.level == warn
                    for s in probe.diagnostics[before:]
                )
            )
        # 200x200 cells of 25 m: 20000x20000 entity cells at 0.25 m
        huge = convert.grid_to_occupancy_grid(
            np.zeros((200, 200), np.int64),
            Header(frame_id='map'),
            convert.map_info((200, 200), 25.0),
        )
        probe.map_pub.publish(huge)
        assert graph.wait_for(lambda: probe.said('map', warn, 'more than max_cells'))
        # a header claiming 20000x20000 cells over a few bytes of data
        liar = OccupancyGrid(header=Header(frame_id='map'), info=convert.map_info((20000, 20000)))
        liar.data = [0] * 16
        probe.map_pub.publish(liar)
        assert graph.wait_for(lambda: len(probe.said('map', warn, 'map rejected')) >= 2)
        count = len(probe.entity_maps)
        probe.map_pub.publish(office.slam_message(stamp=7))
        latched_pub.publish(office.markers())
        assert graph.wait_for(
            lambda: len(probe.entity_maps) > count
            and np.array_equal(probe.grid(), office.EXPECTED)
        )
        # clean markers: the status is OK again
        clean_from = len(probe.diagnostics)
        assert graph.wait_for(
            lambda: any(
                s.name.endswith(': status') and s.level == DiagnosticStatus.OK
                for s in probe.diagnostics[clean_from:]
            )
        )
        assert process.poll() is None, 'the mapper died'
        assert peak_rss_mb(process) < 1024
    finally:
        code, output = interrupt(process)
    assert code == 0, (tmp_path / 'mapper.log').read_text()[-3000:]


def test_a_call_in_flight_is_reported_lost_when_the_server_goes_away(ros_context):
    """
    A server that took the request and left (a restart): GroundingLost, not a wait to the end.

    The server is a real GroundInstruction service whose node is never spun (so the call stays
    in flight) and is then destroyed, as a grounder that stops mid-call.
    """
    import threading

    import rclpy
    from rclpy.node import Node
    from spatial_grounding_interfaces.srv import GroundInstruction
    from spatial_grounding_ros.ros.grounding_client import GroundingClient, GroundingLost

    namespace = unique_namespace('lost')
    context = rclpy.Context()
    rclpy.init(context=context)
    server = Node('spatial_grounder', namespace=namespace, context=context)
    server.create_service(GroundInstruction, 'ground_instruction', lambda req, res: res)
    client = GroundingClient(namespace, context=ros_context.context, timeout=WAIT)
    outcome = []

    def call():
        try:
            outcome.append(client.ground('reach the cell above the fridge'))
        except Exception as exc:  # noqa: BLE001 - the test looks at it
            outcome.append(exc)

    try:
        assert client.wait_for_server()
        thread = threading.Thread(target=call)
        thread.start()
        time.sleep(0.5)  # the request reaches the server, which never takes it
        server.destroy_node()
        thread.join(timeout=WAIT)
        assert not thread.is_alive(), 'the call still waits'
        assert isinstance(outcome[0], GroundingLost), outcome
        assert 'went away with the call in flight' in str(outcome[0])
    finally:
        client.close()
        context.try_shutdown()


def test_a_sequence_sends_its_first_goal_and_the_whole_goal_path(robot):
    """'go to the fridge then the printer': goal_pose is the first step, goal_path both."""
    from nav_msgs.msg import Path as PathMsg
    from std_msgs.msg import String

    graph, namespace, probe, _ = robot
    paths = []
    probe.create_subscription(PathMsg, 'goal_path', paths.append, 10)
    hold_entity_map(graph, probe, namespace, office_grid())
    text = 'go two cells below the fridge then go to the cell left of the fridge'
    probe.instruction_pub.publish(String(data=text))
    assert graph.wait_for(lambda: paths and paths[-1].poses)
    assert len(paths[-1].poses) == 2
    assert probe.goals[-1].pose == paths[-1].poses[0].pose
    # the diagnostic is another topic: it may come after the path
    assert graph.wait_for(lambda: grounder_said(probe, namespace, 'grounding', repr(text)))
    [status] = grounder_said(probe, namespace, 'grounding', repr(text))
    assert {v.key: v.value for v in status.values}['intent'] == 'sequence'


def test_a_stop_sends_an_empty_goal_path_and_no_goal(robot):
    from nav_msgs.msg import Path as PathMsg
    from std_msgs.msg import String

    graph, namespace, probe, _ = robot
    paths = []
    probe.create_subscription(PathMsg, 'goal_path', paths.append, 10)
    hold_entity_map(graph, probe, namespace, office_grid())
    goals = len(probe.goals)
    probe.instruction_pub.publish(String(data='stop'))
    assert graph.wait_for(lambda: paths and not paths[-1].poses)
    assert len(probe.goals) == goals
    assert graph.wait_for(lambda: grounder_said(probe, namespace, 'grounding', "'stop'"))
    [status] = grounder_said(probe, namespace, 'grounding', "'stop'")
    assert {v.key: v.value for v in status.values}['intent'] == 'stop'


def test_a_question_is_answered_in_the_service_and_the_diagnostic(robot):
    from spatial_grounding_ros.ros.grounding_client import GroundingClient

    graph, namespace, probe, _ = robot
    hold_entity_map(graph, probe, namespace, office_grid())
    with GroundingClient(namespace, context=graph.context, timeout=WAIT) as client:
        answer = client.ground('where is the fridge?')
    assert answer.success and answer.intent == 'question' and answer.answer
    assert answer.goal is None and answer.referent is not None


def test_a_negation_and_a_motion_are_declined_with_their_intent(robot):
    """Send no goal for "don't go to the fridge" and "follow me", over the topic or the service."""
    from spatial_grounding_ros.ros.grounding_client import GroundingClient
    from std_msgs.msg import String

    graph, namespace, probe, _ = robot
    hold_entity_map(graph, probe, namespace, office_grid())
    goals = len(probe.goals)
    with GroundingClient(namespace, context=graph.context, timeout=WAIT) as client:
        for text, intent in (("don't go to the fridge", 'negation'), ('follow me', 'unsupported')):
            answer = client.ground(text)
            assert not answer.success and answer.intent == intent and answer.goal is None
            assert answer.reason.startswith(intent)
    said = repr("don't go to the fridge")
    probe.instruction_pub.publish(String(data="don't go to the fridge"))
    assert graph.wait_for(lambda: grounder_said(probe, namespace, 'grounding', said))
    [status] = grounder_said(probe, namespace, 'grounding', said)
    assert {v.key: v.value for v in status.values}['intent'] == 'negation'
    assert len(probe.goals) == goals
