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
import time

from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import OccupancyGrid
import numpy as np
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from spatial_grounding_interfaces.srv import GroundInstruction
from std_msgs.msg import Header

from . import convert
from .qos import BURST
from ..core import topics

# how often a waiting call checks that the server is still there (seconds)
LIVENESS_PERIOD = 0.25


@dataclass
class GroundingAnswer:
    """The service's response as plain Python: success, reason, confidence, goal, ..."""

    success: bool  # False: no goal; `reason` says why (a decline or a bad request)
    reason: str  # '' on success; e.g. 'referent-missing: rock', 'low-confidence: 0.31 < 0.50'
    confidence: float  # calibrated 0..1 probability of the best cell
    goal: PoseStamped | None  # None unless success
    alternatives: list[tuple[PoseStamped, float]] = field(default_factory=list)  # best first
    unknown_words: list[str] = field(default_factory=list)
    # go, stop, question, sequence, negation, unsupported ('' for a refused request)
    intent: str = 'go'
    steps: list[PoseStamped] = field(default_factory=list)  # a sequence's goals, in order
    answer: str = ''  # a question's answer in words
    referent: PoseStamped | None = None  # the landmark's cell centre, None when there is none

    @classmethod
    def from_response(cls, response: GroundInstruction.Response) -> 'GroundingAnswer':
        return cls(
            success=response.success,
            reason=response.reason,
            confidence=float(response.confidence),
            # a stop or a question succeeds without a goal (frame_id '')
            goal=response.goal if response.success and response.goal.header.frame_id else None,
            alternatives=[
                (pose, float(score))
                for pose, score in zip(response.alternatives, response.alternative_scores)
            ],
            unknown_words=list(response.unknown_words),
            intent=response.intent,
            steps=list(response.steps),
            answer=response.answer,
            referent=response.referent if response.referent.header.frame_id else None,
        )


class GroundingLost(ConnectionError):
    """The grounder went away (a restart, a crash) while a call was in flight: no answer comes."""


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
        self.client = self.node.create_client(
            GroundInstruction, topics.GROUND_INSTRUCTION, qos_profile=BURST
        )
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

        GroundingLost when the server leaves while the call is in flight (a restart): the call
        is lost and no answer will come.

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
        deadline = time.monotonic() + timeout
        while not future.done() and time.monotonic() < deadline:
            self.executor.spin_until_future_complete(future, timeout_sec=LIVENESS_PERIOD)
            if not future.done() and not self.client.service_is_ready():
                # the server left the graph: its queue and the call in it are gone
                self.client.remove_pending_request(future)
                raise GroundingLost(
                    f'{self.service_name} went away with the call in flight: it was lost '
                    '(the grounder restarted or stopped); call again once it is back'
                )
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
