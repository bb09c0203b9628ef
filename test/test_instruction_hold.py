# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The grounder node's rules without ROS (core/instruction_hold.py) and its messages for a Grounding.

The hold, expiry and re-ground rule on a clock the test turns; the goal's heading and stamp;
what the node sends for each intent (goal, goal_path, service response, diagnostic level), built
from Groundings as the Grounder makes them.
"""

import math

import numpy as np
import pytest
from spatial_grounding_ros.core.instruction_hold import (
    goal_stamp,
    goal_yaw,
    InstructionHold,
)


class Clock:
    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


def test_an_instruction_waits_for_a_map_and_is_grounded_once():
    hold = InstructionHold(Clock())
    assert hold.take() is None
    assert hold.hold('reach the rock') is None
    assert hold.pending and hold.take() == 'reach the rock'
    assert hold.take() is None  # handed out once
    assert not hold.on_map(reground=False)  # a new map: the next instruction uses it
    assert hold.on_map(reground=True) and hold.take() == 'reach the rock'


def test_a_newer_instruction_supersedes_a_waiting_one_and_says_so():
    hold = InstructionHold(Clock())
    hold.hold('first')
    dropped = hold.hold('second')
    assert (dropped.text, dropped.why) == ('first', 'superseded')
    assert hold.take() == 'second'
    assert hold.hold('third') is None  # 'second' was handed out: it gets its own grounding


def test_expiry_on_the_clock():
    clock = Clock()
    hold = InstructionHold(clock)
    hold.hold('wait for a map')
    clock.now += 29.9
    assert not hold.expired(30.0) and hold.expire(30.0) is None
    clock.now += 0.1
    assert hold.expired(30.0)
    assert hold.expired(0.0) is False  # 0: wait forever
    dropped = hold.expire(30.0)
    assert (dropped.text, dropped.why) == ('wait for a map', 'expired')
    assert hold.text is None and not hold.on_map(reground=True)


def test_drop_returns_only_a_waiting_instruction():
    hold = InstructionHold(Clock())
    assert hold.drop('inactive') is None
    hold.hold('a')
    assert hold.drop('inactive').text == 'a'
    hold.hold('b')
    hold.take()
    assert hold.drop('inactive') is None  # already grounded


class Info:
    """The MapMetaData fields goal_yaw reads, without messages: 4x4 cells of 0.5 m."""

    resolution, width, height = 0.5, 4, 4

    class origin:  # noqa: N801
        class position:  # noqa: N801
            x = y = z = 0.0

        class orientation:  # noqa: N801
            x = y = z = 0.0
            w = 1.0


def test_goal_yaw_for_each_heading():
    cell = (2, 1)
    assert goal_yaw('identity', cell, (0, 1), 1.0, Info) is None
    # the referent two rows north (row 0 is north, +y): yaw +pi/2
    assert goal_yaw('face_referent', cell, (0, 1), None, Info) == pytest.approx(math.pi / 2)
    assert goal_yaw('face_referent', cell, (2, 0), None, Info) == pytest.approx(math.pi)
    assert goal_yaw('face_referent', cell, cell, None, Info) is None
    assert goal_yaw('face_referent', cell, None, None, Info) is None
    assert goal_yaw('keep', cell, (0, 1), 0.3, Info) == 0.3
    assert goal_yaw('keep', cell, None, None, Info) is None
    assert goal_yaw('keep', cell, None, float('nan'), Info) is None
    with pytest.raises(ValueError, match='goal_heading must be one of'):
        goal_yaw('north', cell, None, None, Info)


def test_goal_stamp_rules():
    assert goal_stamp('map', 'map-stamp', lambda: 'now-stamp') == 'map-stamp'
    assert goal_stamp('now', 'map-stamp', lambda: 'now-stamp') == 'now-stamp'
    with pytest.raises(ValueError, match='goal_stamp must be one of'):
        goal_stamp('later', None, lambda: None)


# --- what the node sends for a Grounding (messages, no DDS)

rclpy = pytest.importorskip('rclpy', reason='rclpy is not installed')
pytest.importorskip('spatial_grounding_interfaces', reason='make setup builds the interfaces')


@pytest.fixture(scope='module')
def grounder():
    from spatial_grounding_ros.grounder import Grounder

    return Grounder.from_checkpoint(entities='config/entities_office.yaml')


def office_grid():
    grid = np.zeros((8, 8), dtype=np.int64)  # floor
    grid[2, 5] = 9  # fridge
    return grid


def poser(shape, heading='face_referent'):
    from spatial_grounding_ros.ros import convert
    from spatial_grounding_ros.ros.ground_service import Poser
    from std_msgs.msg import Header

    return Poser(convert.map_info(shape, 0.5), Header(frame_id='map'), heading)


def test_a_goal_its_response_path_and_diagnostic(grounder):
    from diagnostic_msgs.msg import DiagnosticStatus
    from spatial_grounding_interfaces.srv import GroundInstruction
    from spatial_grounding_ros.ros.ground_service import grounding_report, response

    grid = office_grid()
    result = grounder.ground(grid, 'reach the cell two below the fridge')
    assert result.intent == 'go' and result.goal is not None
    p = poser(grid.shape)
    reply = response(GroundInstruction.Response(), result, p)
    assert reply.success and reply.intent == 'go' and reply.reason == ''
    assert reply.steps == [] and reply.answer == ''
    assert reply.goal.header.frame_id == 'map'
    assert reply.referent.header.frame_id == 'map'  # the fridge's cell
    path = p.path(result)
    assert len(path.poses) == 1 and path.poses[0].pose == reply.goal.pose
    level, message, values = grounding_report(result)
    assert values['intent'] == 'go' and 'grounded' in message
    sure = DiagnosticStatus.OK if result.confidence >= 0.5 else DiagnosticStatus.WARN
    assert level == sure


def test_a_decline_and_an_unsure_goal(grounder):
    from dataclasses import replace

    from diagnostic_msgs.msg import DiagnosticStatus
    from spatial_grounding_interfaces.srv import GroundInstruction
    from spatial_grounding_ros.ros.ground_service import grounding_report, response

    grid = np.zeros((6, 6), dtype=np.int64)
    result = grounder.ground(grid, 'reach the cell above the fridge')  # no fridge
    assert result.goal is None and result.reason
    reply = response(GroundInstruction.Response(), result, poser(grid.shape))
    assert not reply.success and reply.reason == result.reason
    assert reply.goal.header.frame_id == ''
    level, _, values = grounding_report(result)
    assert level == DiagnosticStatus.WARN and values['reason'] == result.reason
    sure = grounder.ground(office_grid(), 'reach the cell two below the fridge')
    unsure = replace(sure, confidence=0.3)
    level, message, _ = grounding_report(unsure)
    assert level == DiagnosticStatus.WARN and 'unsure: confidence 0.30 < 0.50' in message
    assert grounding_report(replace(sure, confidence=0.9))[0] == DiagnosticStatus.OK


def test_each_intent_as_the_node_sends_it(grounder):
    """
    Stop, question and sequence groundings (the fields of issue 41) become messages.

    The Grounder does not read these intents yet: the groundings here are real ones with the
    fields set as the contract says the Grounder will set them.
    """
    from dataclasses import replace

    from diagnostic_msgs.msg import DiagnosticStatus
    from spatial_grounding_interfaces.srv import GroundInstruction
    from spatial_grounding_ros.ros.ground_service import grounding_report, response

    grid = office_grid()
    go = grounder.ground(grid, 'reach the cell two below the fridge')
    other = grounder.ground(grid, 'reach the cell left of the fridge')
    p = poser(grid.shape)
    stop = replace(go, intent='stop', goal=None, alternatives=[])
    reply = response(GroundInstruction.Response(), stop, p)
    assert reply.success and reply.intent == 'stop' and reply.goal.header.frame_id == ''
    assert p.path(stop).poses == []  # the stop's empty goal_path
    assert grounding_report(stop)[0] == DiagnosticStatus.OK
    question = replace(go, intent='question', goal=None, answer='the fridge is at row 2')
    reply = response(GroundInstruction.Response(), question, p)
    assert reply.success and reply.answer == 'the fridge is at row 2'
    level, _, values = grounding_report(question)
    assert level == DiagnosticStatus.OK and values['answer'] == 'the fridge is at row 2'
    sequence = replace(go, intent='sequence', steps=[go, other])
    reply = response(GroundInstruction.Response(), sequence, p)
    assert [s.pose for s in reply.steps] == [p.goal(go).pose, p.goal(other).pose]
    assert reply.goal.pose == reply.steps[0].pose
    assert [q.pose for q in p.path(sequence).poses] == [s.pose for s in reply.steps]
    negation = replace(go, intent='negation', goal=None, reason='unsupported: "not"')
    reply = response(GroundInstruction.Response(), negation, p)
    assert not reply.success and reply.intent == 'negation'
    assert grounding_report(negation)[0] == DiagnosticStatus.WARN


def test_auto_heading_faces_a_landmark_the_goal_stands_beside():
    """auto: the goal beside the fridge faces it; any other goal keeps the identity."""
    east = goal_yaw('auto', (1, 1), (1, 2), None, Info, beside=True)
    assert east == pytest.approx(0.0)
    north = goal_yaw('auto', (1, 1), (0, 1), None, Info, beside=True)
    assert north == pytest.approx(math.pi / 2)
    assert goal_yaw('auto', (1, 1), (0, 1), None, Info) is None
