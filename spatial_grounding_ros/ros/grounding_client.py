# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
A blocking client of the grounder's ground_instruction service, as nav2_simple_commander is.

    import rclpy
    from spatial_grounding_ros.ros.grounding_client import GroundingClient

    rclpy.init()
    client = GroundingClient(namespace='/robot1')
    answer = client.ground('go to the cell north of the rock', entity_map=grid)  # or None
    if answer.success:
        navigator.goToPose(answer.goal)
    else:
        print('declined:', answer.reason, answer.confidence)
    client.close()

The client spins a node of its own while it waits, so the caller never handles a future.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import OccupancyGrid
import numpy as np
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from spatial_grounding_interfaces.srv import GroundInstruction
from std_msgs.msg import Header

from . import convert
from ..core import topics


@dataclass
class GroundingAnswer:
    """The service's response as plain Python: success, reason, confidence, goal, ..."""

    success: bool  # False: no goal; `reason` says why (a decline or a bad request)
    reason: str  # '' on success; e.g. 'referent-missing: rock', 'low-confidence: 0.31 < 0.50'
    confidence: float  # calibrated 0..1 probability of the best cell
    goal: PoseStamped | None  # None unless success
    alternatives: list[tuple[PoseStamped, float]] = field(default_factory=list)  # best first
    unknown_words: list[str] = field(default_factory=list)

    @classmethod
    def from_response(cls, response: GroundInstruction.Response) -> 'GroundingAnswer':
        return cls(
            success=response.success,
            reason=response.reason,
            confidence=float(response.confidence),
            goal=response.goal if response.success else None,
            alternatives=[
                (pose, float(score))
                for pose, score in zip(response.alternatives, response.alternative_scores)
            ],
            unknown_words=list(response.unknown_words),
        )


class GroundingClient:
    """
    Ask the grounder in `namespace` to ground instructions; each call blocks for the answer.

    `context`: an rclpy Context (default: the global one, which must be initialised).
    `timeout`: seconds a call waits when it is given none (a busy machine may want more).
    """

    def __init__(
        self,
        namespace: str = '',
        node_name: str = 'grounding_client',
        context=None,
        timeout: float = 10.0,
    ):
        self.timeout = timeout
        self.node = Node(node_name, namespace=namespace or '/', context=context)
        self.client = self.node.create_client(GroundInstruction, topics.GROUND_INSTRUCTION)
        self.executor = SingleThreadedExecutor(context=self.node.context)
        self.executor.add_node(self.node)

    @property
    def service_name(self) -> str:
        return self.client.srv_name

    def wait_for_server(self, timeout: float | None = None) -> bool:
        """Wait until the grounder (configured: it serves from configure on) is there."""
        return self.client.wait_for_service(timeout_sec=timeout or self.timeout)

    def ground(
        self,
        instruction: str,
        entity_map: OccupancyGrid | np.ndarray | None = None,
        timeout: float | None = None,
        frame_id: str = 'map',
    ) -> GroundingAnswer:
        """
        Ground `instruction`; the answer, or TimeoutError after `timeout` seconds.

        `timeout`: default the client's.

        `entity_map`: an OccupancyGrid, a (H, W) grid of entity indices (row 0 = north; 1 m
        cells, origin 0, 0, in `frame_id`), or None for the map the grounder holds.
        """
        timeout = timeout or self.timeout
        request = GroundInstruction.Request(instruction=instruction)
        if isinstance(entity_map, OccupancyGrid):
            request.entity_map = entity_map
        elif entity_map is not None:
            request.entity_map = convert.grid_to_occupancy_grid(
                np.asarray(entity_map), Header(frame_id=frame_id)
            )
        if not self.wait_for_server(timeout):
            raise TimeoutError(f'no {self.service_name} service within {timeout} s')
        future = self.client.call_async(request)
        self.executor.spin_until_future_complete(future, timeout_sec=timeout)
        if not future.done():
            self.client.remove_pending_request(future)
            raise TimeoutError(f'{self.service_name} did not answer within {timeout} s')
        return GroundingAnswer.from_response(future.result())

    def close(self) -> None:
        self.executor.remove_node(self.node)
        self.executor.shutdown()
        self.node.destroy_node()

    def __enter__(self) -> 'GroundingClient':
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def ground(instruction: str, entity_map=None, namespace: str = '', timeout: float = 10.0):
    """Return one GroundingAnswer, initialising (and shutting down) rclpy if needed."""
    owns = not rclpy.ok()
    if owns:
        rclpy.init()
    try:
        with GroundingClient(namespace) as client:
            return client.ground(instruction, entity_map, timeout)
    finally:
        if owns:
            rclpy.try_shutdown()
