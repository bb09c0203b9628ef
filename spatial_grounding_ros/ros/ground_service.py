# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The grounder node's goal poses and its ground_instruction service.

goal_pose gives a cell the orientation of goal_heading and the stamp of goal_stamp; answer
serves spatial_grounding_interfaces/srv/GroundInstruction for a GrounderNode.
"""

from __future__ import annotations

from geometry_msgs.msg import PoseStamped
from std_msgs.msg import Header

from . import convert
from ..grounder import Grounding


def goal_pose(node, cell, result: Grounding, info, header: Header) -> PoseStamped:
    """
    Return the pose of `cell`, oriented by goal_heading and stamped by goal_stamp.

    face_referent: from the cell's centre toward the referent's (identity when there is none
    or it is the cell); keep: the latest robot_pose's yaw (identity before one arrives).
    """
    heading = node.param('goal_heading')
    yaw = None
    if heading == 'face_referent':
        yaw = convert.yaw_toward(cell, result.referent, info)
    elif heading == 'keep':
        yaw = node.robot_yaw
    stamp = header.stamp
    if node.param('goal_stamp') == 'now':
        stamp = node.get_clock().now().to_msg()
    return convert.cell_to_pose(cell, info, header.frame_id, stamp, yaw)


def answer(node, request, response):
    """
    Answer GroundInstruction: one grounding, nothing published, nothing held.

    A decline is success false with its reason; bad input (a bad map, an empty
    instruction, no map at all) success false with the error; never an exception.
    """
    try:
        node.check_text(request.instruction)
        map_msg = request.entity_map
        if len(map_msg.data) == 0:
            if node.grid is None:
                raise ValueError(
                    'the request has no entity_map (empty data) and no valid entity_map '
                    'is held'
                )
            grid, map_msg = node.grid, node.map_msg
        else:
            grid = convert.occupancy_grid_to_grid(map_msg, node.param('max_cells'))
            node.grounder.check_grid(grid)
        result = node.run_grounder(grid, request.instruction, map_msg)
    except Exception as exc:  # noqa: BLE001 - an answer, never a crash of the node
        response.success = False
        response.reason = str(exc) if isinstance(exc, ValueError) else (
            f'{type(exc).__name__}: {exc}'
        )
        node.get_logger().debug(f'ground_instruction refused: {response.reason}')
        return response
    info, header = map_msg.info, node.output_header(map_msg)
    response.success = result.goal is not None
    response.reason = result.reason or ''
    response.confidence = result.confidence
    if result.goal is not None:
        response.goal = goal_pose(node, result.goal, result, info, header)
    response.alternatives = [
        goal_pose(node, cell, result, info, header) for cell, _ in result.alternatives
    ]
    response.alternative_scores = [p for _, p in result.alternatives]
    response.unknown_words = list(result.unknown_words)
    return response
