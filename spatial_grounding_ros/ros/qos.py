# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""The package's two QoS profiles; every node, client and recorder takes its profiles here."""

from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

# Like /map: the latest message waits for late subscribers (RViz, a grounder started later, a
# recorder). Maps, instructions, value maps and the gridworld's truth topics.
LATCHED = QoSProfile(
    depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)
# One message per event (a move's agent_pose, reward and terminated; an action): deep enough
# that a client pairing the topics by count never loses one.
STREAM = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
# Services and instructions under bursts: a request the node has not yet taken waits here, so
# deep that a burst is taken and answered (or refused as busy) rather than lost in the queue.
BURST = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
