# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""A latched output whose message is built only once someone subscribes."""

from __future__ import annotations

import threading
from typing import Callable

from rclpy.event_handler import PublisherEventCallbacks, QoSPublisherMatchedInfo
from rclpy.lifecycle import LifecycleNode

from .qos import LATCHED


class LatchedOutput:
    """
    A latched lifecycle topic (the value maps, the relation map) published on demand.

    Building these messages from a grounding is most of what the grounder does after it sends
    the goal (some 0.15 ms of a 10x10 map's), and with no one subscribed it is work for no
    one. So each keeps the maker of its latest message: with a subscriber matched it builds
    and publishes at once; else it publishes when one matches (the publisher's matched event),
    as a latched topic would have kept it for that subscriber.
    """

    def __init__(self, node: LifecycleNode, msg_type, topic: str):
        self.lock = threading.Lock()  # offers come from the topic grounding thread too
        self.pending: Callable[[], object] | None = None
        self.publisher = node.create_lifecycle_publisher(
            msg_type, topic, LATCHED, event_callbacks=PublisherEventCallbacks(matched=self.matched)
        )

    def offer(self, make: Callable[[], object]) -> None:
        """Publish `make()` now if anyone subscribes, else when someone does."""
        with self.lock:
            wanted = self.publisher.get_subscription_count() > 0
            self.pending = None if wanted else make
        if wanted:
            self.publisher.publish(make())

    def matched(self, info: QoSPublisherMatchedInfo) -> None:
        # while inactive the maker stays: the node sends nothing then (a lifecycle publisher)
        with self.lock:
            if info.current_count_change <= 0 or not self.publisher.is_activated:
                return
            make, self.pending = self.pending, None
        if make is not None:
            self.publisher.publish(make())
