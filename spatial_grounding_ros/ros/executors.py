# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Where a node's callbacks run: the grounder's worker thread and its serving executor.

Short callbacks (inputs, status, lifecycle, a small map's grounding) run in the spinning thread,
a large map's topic groundings on a Worker that the inputs wake, and requests that may wait (the
grounder's service) on a pool.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
import threading
from typing import Callable

from rclpy.executors import (
    ConditionReachedException,
    ShutdownException,
    SingleThreadedExecutor,
    TimeoutException,
)
from rclpy.node import Node


class Worker:
    """A thread that runs `work` each time it is woken; a wake while it works runs it again."""

    def __init__(self, work: Callable[[], None], name: str):
        self.work, self.wanted, self.closing = work, threading.Event(), False
        self.working = False
        self.thread = threading.Thread(target=self.run, name=name, daemon=True)
        self.thread.start()

    def wake(self) -> None:
        """Run the work (again)."""
        self.wanted.set()

    def idle(self) -> bool:
        """Whether the work neither runs nor waits to (a wake made before is under way)."""
        return not (self.working or self.wanted.is_set())

    def stop(self) -> None:
        """End the thread once the work under way has ended."""
        self.closing = True
        self.wanted.set()
        self.thread.join()

    def run(self) -> None:
        while True:
            self.wanted.wait()
            self.working = True
            self.wanted.clear()
            try:
                if self.closing:
                    return
                self.work()
            finally:
                self.working = False


class ServingExecutor(SingleThreadedExecutor):
    """
    Run callbacks in the spinning thread, those of `pooled` callback groups on a thread pool.

    The pooled ones are requests that may wait (the grounder's service, for the model); the
    rest are short. rclpy's MultiThreadedExecutor hands every callback to its pool, and until a
    pool thread has started one, the spinning thread finds it still to do and hands it over
    again, and again: a busy loop that, with the grounding thread wanting the GIL, held an
    instruction 10-20 ms at p50 and hundreds at p99 on 2 cores. Here the spinning thread waits
    for a pooled callback to start before it waits for more work.
    """

    def __init__(self, pooled: tuple, threads: int, context=None):
        super().__init__(context=context)
        self.pooled = pooled
        self.pool = ThreadPoolExecutor(threads, thread_name_prefix='requests')

    def _spin_once_impl(self, timeout_sec=None, wait_condition=lambda: False) -> None:
        try:
            handler, entity, _ = self.wait_for_ready_callbacks(timeout_sec, None, wait_condition)
        except (ShutdownException, TimeoutException, ConditionReachedException):
            return
        if entity is None or entity.callback_group not in self.pooled:
            handler()
            handler.result()  # raise what the callback raised, as rclpy's executors do
            return
        started = threading.Event()

        def run():
            started.set()
            handler()

        self.pool.submit(run)
        started.wait()

    def shutdown(self, timeout_sec: float | None = None) -> bool:
        done = super().shutdown(timeout_sec)
        self.pool.shutdown(wait=False)
        return done


def make_executor(node: Node, context=None):
    """
    Return the executor a node spins in.

    A ServingExecutor for a node whose requests may wait (node.pooled_groups(), on
    node.request_threads() threads: the grounder's service), else a SingleThreadedExecutor.
    """
    context = context or node.context
    if not hasattr(node, 'pooled_groups'):
        return SingleThreadedExecutor(context=context)
    return ServingExecutor(node.pooled_groups(), node.request_threads(), context=context)
