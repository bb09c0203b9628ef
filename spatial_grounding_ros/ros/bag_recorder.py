"""Record topics to a rosbag2 MCAP bag without the ros2 CLI: subscriptions with raw=True
hand over the serialized CDR bytes, which bags.BagWriter stores unchanged (so `ros2 bag
info/play` of Jazzy read the result). Latched topics are subscribed transient local."""
from __future__ import annotations

import importlib
from pathlib import Path

from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from ..bags import BagWriter

LATCHED_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
STREAM_QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)


def message_class(msgtype: str):
    """'std_msgs/msg/String' -> std_msgs.msg.String."""
    package, kind, name = msgtype.split("/")
    return getattr(importlib.import_module(f"{package}.{kind}"), name)


class BagRecorder(Node):
    """Writes every message of `topics` ({name: 'pkg/msg/Type'}) to a new bag at `path`;
    names in `latched` are recorded (and marked in the bag) as transient local."""

    def __init__(self, path: str | Path, topics: dict[str, str], latched: set[str] = frozenset(),
                 node_name: str = "bag_recorder", **node_options):
        super().__init__(node_name, **node_options)
        self.bag = BagWriter(path, latched={self.resolve_topic_name(t) for t in latched})
        self.bag.__enter__()
        for topic, msgtype in topics.items():
            full = self.resolve_topic_name(topic)
            self.create_subscription(
                message_class(msgtype), topic,
                lambda data, full=full, msgtype=msgtype: self.bag.write(
                    full, msgtype, self.get_clock().now().nanoseconds, data),
                LATCHED_QOS if topic in latched else STREAM_QOS, raw=True)

    @property
    def counts(self) -> dict[str, int]:
        return dict(self.bag.counts)

    def close(self) -> None:
        self.bag.close()

    def destroy_node(self) -> None:
        self.close()
        super().destroy_node()
