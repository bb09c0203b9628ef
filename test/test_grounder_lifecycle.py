# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The grounder as a lifecycle node, driven over real DDS by a lifecycle client.

The grounder as a lifecycle node, driven over real DDS by a lifecycle client (what Nav2's
lifecycle manager does): with autostart false it waits unconfigured; configure loads the
model and creates the topics; only while active does an instruction get a goal; deactivate
drops the held instruction; cleanup releases the model, the map and the topics; a configure
that cannot load the checkpoint fails and leaves the node unconfigured and serving.
"""

import time

import numpy as np
import pytest

pytest.importorskip('rclpy', reason='rclpy is not installed')

from diagnostic_msgs.msg import DiagnosticStatus  # noqa: E402, I100
from grounder_helpers import (  # noqa: E402
    ANY_CONFIDENCE,
    make_probe,
    PUDDLEWORLD_TABLE,
    random_checkpoint,
    unique_namespace,
)
from lifecycle_msgs.msg import State, Transition  # noqa: E402
from lifecycle_msgs.srv import ChangeState, GetState  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from spatial_grounding_ros.data.generator import generate  # noqa: E402
from spatial_grounding_ros.ros import convert  # noqa: E402
from spatial_grounding_ros.ros.grounder_node import GrounderNode  # noqa: E402
from std_msgs.msg import Header  # noqa: E402

WORLDS = generate(2, seed=4, mode='local')
NO_GOAL_WAIT = 0.5  # after the diagnostic, how long a stray goal would have had to arrive


class LifecycleClient:
    """Calls <node>/change_state and <node>/get_state from a node of its own."""

    def __init__(self, graph, node_name: str):
        self.graph = graph
        caller = graph.add(
            Node('lifecycle_manager', namespace=unique_namespace('manager'), context=graph.context)
        )
        self.change = caller.create_client(ChangeState, f'{node_name}/change_state')
        self.get = caller.create_client(GetState, f'{node_name}/get_state')
        assert self.change.wait_for_service(timeout_sec=30)
        assert self.get.wait_for_service(timeout_sec=30)

    def call(self, client, request):
        future = client.call_async(request)
        assert self.graph.wait_for(future.done, timeout=60), 'no answer from the node'
        return future.result()

    def state(self) -> str:
        return self.call(self.get, GetState.Request()).current_state.label

    def transition(self, transition_id: int) -> bool:
        request = ChangeState.Request(transition=Transition(id=transition_id))
        return self.call(self.change, request).success


@pytest.fixture(scope='module')
def checkpoint(tmp_path_factory):
    return random_checkpoint(tmp_path_factory.mktemp('ckpt') / 'random.pt')


def start(graph, namespace, checkpoint):
    grounder = graph.add(
        GrounderNode(
            context=graph.context,
            namespace=namespace,
            parameter_overrides=[
                Parameter('checkpoint', value=str(checkpoint)),
                PUDDLEWORLD_TABLE,
                ANY_CONFIDENCE,
                Parameter('autostart', value=False),
                Parameter('torch_threads', value=0),
            ],
        )
    )
    probe = graph.add(make_probe(graph.context, namespace, grounder.get_fully_qualified_name()))
    return grounder, probe, LifecycleClient(graph, grounder.get_fully_qualified_name())


def instruct(graph, probe, text) -> tuple[list, list]:
    """Publish an instruction; (the diagnostics it caused, any goals after a pause)."""
    before = probe.counts()
    probe.publish_instruction(text)
    assert graph.wait_for(lambda: probe.new('diagnostics', before)), 'no diagnostic'
    time.sleep(NO_GOAL_WAIT)
    return probe.new('diagnostics', before), probe.new('goals', before)


def test_transitions_over_dds_and_goals_only_while_active(ros_context, checkpoint):
    graph = ros_context
    namespace = unique_namespace('lifecycle_test')
    grounder, probe, manager = start(graph, namespace, checkpoint)
    grid, text = WORLDS.grids[0], WORLDS.instructions[0]

    # autostart false: unconfigured, no model, no topics, waiting for a manager
    assert manager.state() == 'unconfigured'
    assert grounder.grounder is None
    assert probe.instruction_pub.get_subscription_count() == 0
    assert probe.count_publishers(f'{namespace}/goal_pose') == 0

    # configure: the model is loaded, the topics exist, a map is held; no goal (inactive)
    assert manager.transition(Transition.TRANSITION_CONFIGURE)
    assert manager.state() == 'inactive' and grounder.grounder is not None
    assert graph.wait_for(probe.connected, timeout=30), 'topics not created on configure'
    message = probe.publish_map(grid)
    assert graph.wait_for(lambda: probe.holds(message))
    [status], goals = instruct(graph, probe, text)
    assert status.level == DiagnosticStatus.WARN and 'the node is inactive' in status.message
    assert not goals, 'a goal was published while inactive'

    # activate: the same instruction gets its goal
    assert manager.transition(Transition.TRANSITION_ACTIVATE)
    assert manager.state() == 'active'
    statuses, goals = instruct(graph, probe, text)
    # OK, or WARN for a goal less than even odds to be right (the random model's)
    assert [s.name.endswith(': grounding') for s in statuses] == [True] and len(goals) == 1
    assert statuses[0].level != DiagnosticStatus.ERROR and 'grounded' in statuses[0].message

    # deactivate: no goal for a new instruction, nor for the held one on a new map
    grounder.set_parameters([Parameter('reground_on_map_change', value=True)])
    assert manager.transition(Transition.TRANSITION_DEACTIVATE)
    assert manager.state() == 'inactive'
    before = probe.counts()
    message = probe.publish_map(WORLDS.grids[1])
    assert graph.wait_for(lambda: probe.holds(message))
    [status], goals = instruct(graph, probe, text)
    assert 'the node is inactive' in status.message
    assert not goals and not probe.new('goals', before), 'a goal while inactive'

    # activate again: no stale goal; a new instruction is grounded on the held map
    assert manager.transition(Transition.TRANSITION_ACTIVATE)
    time.sleep(NO_GOAL_WAIT)
    assert not probe.new('goals', before), 'reactivation sent a goal for an old instruction'
    statuses, goals = instruct(graph, probe, WORLDS.instructions[1])
    # OK, or WARN for a goal less than even odds to be right (the random model's)
    assert [s.name.endswith(': grounding') for s in statuses] == [True] and len(goals) == 1
    assert statuses[0].level != DiagnosticStatus.ERROR and 'grounded' in statuses[0].message

    # deactivate + cleanup: model, map and topics released
    assert manager.transition(Transition.TRANSITION_DEACTIVATE)
    assert manager.transition(Transition.TRANSITION_CLEANUP)
    assert manager.state() == 'unconfigured'
    assert grounder.grounder is None and grounder.map_msg is None
    assert graph.wait_for(
        lambda: (
            probe.instruction_pub.get_subscription_count() == 0
            and probe.count_publishers(f'{namespace}/goal_pose') == 0
        ),
        timeout=30,
    ), 'topics not released on cleanup'

    # configure again works, and shutdown finalizes
    assert manager.transition(Transition.TRANSITION_CONFIGURE)
    assert manager.transition(Transition.TRANSITION_INACTIVE_SHUTDOWN)
    assert manager.state() == 'finalized' and grounder.grounder is None


def test_a_configure_that_cannot_load_fails_and_the_node_keeps_serving(ros_context, tmp_path):
    graph = ros_context
    namespace = unique_namespace('lifecycle_bad_test')
    grounder, probe, manager = start(graph, namespace, tmp_path / 'missing.pt')
    assert not manager.transition(Transition.TRANSITION_CONFIGURE)
    assert manager.state() == 'unconfigured' and grounder.grounder is None
    assert 'missing.pt: checkpoint not found' in grounder.configure_error
    assert not manager.transition(Transition.TRANSITION_ACTIVATE)  # not from unconfigured
    assert manager.state() == 'unconfigured'


def test_autostart_is_active_at_once(ros_context, checkpoint):
    """The default: `ros2 run` alone configures and activates."""
    graph = ros_context
    grounder = graph.add(
        GrounderNode(
            context=graph.context,
            namespace=unique_namespace('autostart_test'),
            parameter_overrides=[
                Parameter('checkpoint', value=str(checkpoint)),
                PUDDLEWORLD_TABLE,
                ANY_CONFIDENCE,
                Parameter('torch_threads', value=0),
            ],
        )
    )
    manager = LifecycleClient(graph, grounder.get_fully_qualified_name())
    assert manager.state() == 'active'
    assert State.PRIMARY_STATE_ACTIVE == 3


@pytest.mark.parametrize('held', ['grounded', 'waiting for a map'])
def test_reactivation_never_grounds_an_instruction_from_before_the_pause(
    ros_context, checkpoint, held
):
    """
    Check docs/ros.md's Lifecycle: deactivate drops the held instruction.

    "activating again never sends a goal for an old instruction; maps are still taken and
    held". An instruction is held either way the node holds one: grounded (then, with
    reground_on_map_change, grounded again on each new map) or waiting for a map. Without a
    pause the next map grounds it (the control). After deactivate and activate, neither a map
    taken while inactive nor one after activation grounds it: the only grounding after the
    pause is the new instruction's. (Each grounding publishes its goal and a diagnostic naming
    the instruction; /diagnostics from one node is one reliable, ordered stream, so a stale
    grounding's would have come before the new one's.)
    """
    graph = ros_context
    grounder, probe, manager = start(graph, unique_namespace('lifecycle_drop_test'), checkpoint)
    assert manager.transition(Transition.TRANSITION_CONFIGURE)
    assert manager.transition(Transition.TRANSITION_ACTIVATE)
    assert graph.wait_for(probe.connected), 'probe and grounder never matched'
    grounder.set_parameters([Parameter('reground_on_map_change', value=True)])
    grid = WORLDS.grids[0]
    old, new = 'reach cell with circle', 'reach cell with star'  # both on `grid`

    def said(text, level=DiagnosticStatus.WARN):
        before = probe.counts()
        return lambda: any(
            s.level == level and text in s.message for s in probe.new('diagnostics', before)
        )

    def groundings(since) -> list[str]:
        statuses = probe.new('diagnostics', since)
        return [s.message for s in statuses if s.name.endswith(': grounding')]

    def hold_map(grid):
        message = probe.publish_map(grid)
        assert graph.wait_for(lambda: probe.holds(message)), 'no OK diagnostic for the map'

    def hold_instruction(text) -> dict:
        """Leave `text` held as `held` says, and nothing else in flight; the counts then."""
        dropped = said('instruction is empty')
        probe.publish_instruction(' ')  # a rejected instruction drops any held one
        assert graph.wait_for(dropped)
        before = probe.counts()
        if held == 'grounded':
            hold_map(grid)
            probe.publish_instruction(text)
            assert graph.wait_for(lambda: probe.new('goals', before) and groundings(before))
        else:
            rejected = said('entity_map rejected')
            bad = convert.grid_to_occupancy_grid(np.full((3, 3), 99), Header(frame_id='map'))
            probe.publish_map(message=bad)  # a rejected map drops the held one
            assert graph.wait_for(rejected)
            holding = said('holding instruction')
            probe.publish_instruction(text)
            assert graph.wait_for(holding)
        return probe.counts()

    # the control: without a pause, the held instruction is grounded on the next map
    after = hold_instruction(old)
    hold_map(grid)
    assert graph.wait_for(lambda: probe.new('goals', after) and groundings(after))
    assert 'circle' in groundings(after)[0], 'the control did not ground the held instruction'

    # the pause: deactivate, a map while inactive (taken and held), activate, another map
    after = hold_instruction(old)
    assert manager.transition(Transition.TRANSITION_DEACTIVATE)
    hold_map(WORLDS.grids[1])
    assert manager.transition(Transition.TRANSITION_ACTIVATE)
    hold_map(grid)
    probe.publish_instruction(new)
    assert graph.wait_for(
        lambda: probe.new('goals', after) and any('star' in m for m in groundings(after))
    ), 'no goal for the new instruction'
    assert len(groundings(after)) == 1, (
        f'grounded after the pause: {groundings(after)}, one from before the pause'
    )
