# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
What the grounder node sends for a Grounding, as messages: no node, no state.

Poser turns cells into poses on one map (goal_heading, goal_stamp, the frame); response() fills
a GroundInstruction response, path() a sequence's nav_msgs/Path, report() says in a diagnostic's
level, words and values what a grounding came to. An intent the node does not know is taken as
'go'.
"""

from __future__ import annotations

from dataclasses import dataclass

from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import MapMetaData, Path
from std_msgs.msg import Header

from . import convert
from ..core.instruction_hold import goal_yaw
from ..grounder import Grounding

# answered without a goal: a stop, a question
NO_GOAL_INTENTS = ('stop', 'question')
# a goal less likely than this to be the cell meant is reported WARN, not OK
SURE = 0.5


def intent(result: Grounding) -> str:
    return getattr(result, 'intent', 'go') or 'go'


def answered(result: Grounding) -> bool:
    """Whether the grounding answers the instruction: a goal, a stop, a question's answer."""
    if result.reason is not None:
        return False
    return result.goal is not None or intent(result) in NO_GOAL_INTENTS


@dataclass
class Poser:
    """Poses of cells of one map: its info, the outputs' header, goal_heading, the robot's yaw."""

    info: MapMetaData
    header: Header  # frame_id, and the stamp goal_stamp chose
    heading: str
    robot_yaw: float | None = None

    def pose(self, cell, referent=None, beside: bool = False) -> PoseStamped:
        yaw = goal_yaw(self.heading, cell, referent, self.robot_yaw, self.info, beside)
        return convert.cell_to_pose(cell, self.info, self.header.frame_id, self.header.stamp, yaw)

    def goal(self, result: Grounding) -> PoseStamped | None:
        if result.goal is None:
            return None
        return self.pose(result.goal, result.referent, getattr(result, 'beside', False))

    def referent(self, result: Grounding) -> PoseStamped:
        """Return the referent's cell centre (identity heading); frame_id '' when there is none."""
        if result.referent is None:
            return PoseStamped()
        return convert.cell_to_pose(
            result.referent, self.info, self.header.frame_id, self.header.stamp
        )

    def steps(self, result: Grounding) -> list[PoseStamped]:
        """Return a sequence's goals in order; an empty pose for a step without one."""
        return [self.goal(step) or PoseStamped() for step in getattr(result, 'steps', ())]

    def path(self, result: Grounding) -> Path:
        """
        goal_path's message: a sequence's goals in order, the goal alone for 'go'.

        Empty (no poses) for a stop: a follower stops.
        """
        poses = []
        if intent(result) == 'sequence':
            poses = [p for p in self.steps(result) if p.header.frame_id]
        elif result.goal is not None:
            poses = [self.goal(result)]
        return Path(header=self.header, poses=poses)


def refuse(response, reason: str):
    """Return a GroundInstruction response that grounded nothing, with the reason."""
    response.success = False
    response.reason = reason
    response.intent = ''
    return response


def response(response, result: Grounding, poser: Poser):
    """Fill a GroundInstruction response with `result`."""
    response.success = answered(result)
    response.reason = result.reason or ''
    response.confidence = float(result.confidence)
    response.intent = intent(result)
    goal = poser.goal(result)
    if goal is not None and result.reason is None:
        response.goal = goal
    response.alternatives = [poser.pose(cell, result.referent) for cell, _ in result.alternatives]
    response.alternative_scores = [float(p) for _, p in result.alternatives]
    response.unknown_words = list(result.unknown_words)
    response.steps = poser.steps(result) if response.intent == 'sequence' else []
    response.answer = getattr(result, 'answer', None) or ''
    response.referent = poser.referent(result)
    return response


def grounding_report(result: Grounding) -> tuple[bytes, str, dict]:
    """Return the grounding diagnostic's (level, message, values) for `result`."""
    kind, text = intent(result), result.instruction
    values = {'intent': kind, 'confidence': f'{result.confidence:.3f}'}
    if result.reason is not None or not answered(result):
        values['reason'] = result.reason
        return DiagnosticStatus.WARN, f'declined {text!r}: {result.reason}; no goal sent', values
    if kind == 'stop':
        return DiagnosticStatus.OK, f'stop ({text!r}): no goal; an empty goal_path sent', values
    if kind == 'question':
        values['answer'] = result.answer or ''
        return DiagnosticStatus.OK, f'answered {text!r}: {result.answer}', values
    message = f'grounded {text!r} at cell (row, col) {result.goal}'
    values.update(goal_row=result.goal[0], goal_col=result.goal[1])
    if kind == 'sequence':
        values['steps'] = len(result.steps)
        message += f', the first of {len(result.steps)} steps (goal_path)'
    if result.unknown_words:
        message += f'; ignored unknown words {result.unknown_words}'
    if result.confidence < SURE:
        message += f'; unsure: confidence {result.confidence:.2f} < {SURE:.2f}'
        return DiagnosticStatus.WARN, message, values
    return DiagnosticStatus.OK, message, values
