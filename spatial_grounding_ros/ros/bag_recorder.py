# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Record topics to a rosbag2 MCAP bag without the ros2 CLI, as `ros2 bag record` would.

Subscriptions with raw=True hand over the serialized CDR bytes, which bags.BagWriter stores
unchanged. Each message's log_time is its reception time from the middleware (the message
info's received_timestamp, taken as the sample arrives, not when a busy Python thread gets
round to the callback) and its publish_time the publisher's source timestamp. A topic's
connection records the publishers' offered QoS and type hash as the graph reports them when
its first message arrives. Latched topics are subscribed transient local.

RecordingThread runs a recorder in an executor thread of its own, so that it does nothing
but record while the caller's thread does other work (the demo draws PNGs).
"""

from __future__ import annotations

import importlib
from pathlib import Path
import threading

from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.topic_endpoint_info import TopicEndpointInfo

from .qos import LATCHED, STREAM
from ..data.bags import BagWriter, duration


def message_class(msgtype: str):
    """'std_msgs/msg/String' -> std_msgs.msg.String."""
    package, kind, name = msgtype.split('/')
    return getattr(importlib.import_module(f'{package}.{kind}'), name)


def offered_qos(endpoint: TopicEndpointInfo):
    """
    Return a publisher's QoS as the graph reports it.

    A publisher's QoS as the graph reports it (history and depth are not discovered:
    'unknown' and 0, as `ros2 bag record` stores them too) -> a rosbags Qos.
    """
    from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability

    q = endpoint.qos_profile
    # rclpy's and rosbags' policy enums share their member names
    return Qos(
        history=QosHistory[q.history.name],
        depth=q.depth,
        reliability=QosReliability[q.reliability.name],
        durability=QosDurability[q.durability.name],
        deadline=duration(q.deadline.nanoseconds),
        lifespan=duration(q.lifespan.nanoseconds),
        liveliness=QosLiveliness[q.liveliness.name],
        liveliness_lease_duration=duration(q.liveliness_lease_duration.nanoseconds),
        avoid_ros_namespace_conventions=q.avoid_ros_namespace_conventions,
    )


class BagRecorder(Node):
    """
    Writes every message of `topics` ({name: 'pkg/msg/Type'}) to a new bag at `path`.

    Names in `latched` are subscribed transient local.
    """

    def __init__(
        self,
        path: str | Path,
        topics: dict[str, str],
        latched: set[str] = frozenset(),
        node_name: str = 'bag_recorder',
        **node_options,
    ):
        super().__init__(node_name, **node_options)
        self.bag = BagWriter(path, latched={self.resolve_topic_name(t) for t in latched})
        self.bag.__enter__()
        self.lock = threading.Lock()  # close() may come from another thread than callbacks
        for topic, msgtype in topics.items():
            full = self.resolve_topic_name(topic)
            self.create_subscription(
                message_class(msgtype),
                topic,
                lambda data, info, full=full, msgtype=msgtype: self.record(
                    full, msgtype, data, info
                ),
                LATCHED if topic in latched else STREAM,
                raw=True,
            )

    def record(self, topic: str, msgtype: str, data: bytes, info: dict) -> None:
        with self.lock:
            if self.bag.writer is None:  # closed
                return
            new = topic not in self.bag.connections
            publishers = self.get_publishers_info_by_topic(topic) if new else []
            self.bag.write(
                topic,
                msgtype,
                info['received_timestamp'],
                data,
                publish_time_ns=info['source_timestamp'],
                offered_qos=[offered_qos(p) for p in publishers] or None,
                type_hash=str(publishers[0].topic_type_hash) if publishers else None,
            )

    @property
    def counts(self) -> dict[str, int]:
        return dict(self.bag.counts)

    def close(self) -> None:
        with self.lock:
            self.bag.close()

    def destroy_node(self) -> None:
        self.close()
        super().destroy_node()


class RecordingThread:
    """
    A BagRecorder spinning in a thread of its own (same rclpy context as the caller).

    recording = RecordingThread(path, topics, latched, namespace='/demo')
    ...
    recording.stop()   # stops the thread, closes the bag
    """

    def __init__(self, *args, **kwargs):
        self.recorder = BagRecorder(*args, **kwargs)
        self.executor = SingleThreadedExecutor(context=self.recorder.context)
        self.executor.add_node(self.recorder)
        self.thread = threading.Thread(target=self._spin, name='bag_recorder', daemon=True)
        self.thread.start()

    def _spin(self) -> None:
        try:
            self.executor.spin()
        except ExternalShutdownException:
            pass

    @property
    def counts(self) -> dict[str, int]:
        return self.recorder.counts

    def stop(self) -> None:
        self.executor.shutdown()
        self.thread.join(timeout=10)
        self.recorder.destroy_node()
