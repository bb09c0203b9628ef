# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Shared test set-up.

Tests that need the real data sets use the `data_dir` fixture, which skips them (with the reason)
when ../shared/data is absent.
"""

import os
from pathlib import Path
import random

import pytest

REPO = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get('SPATIAL_GROUNDING_DATA', REPO.parent / 'shared' / 'data'))

# How long RosGraph.wait_for waits for a thing that should happen before it calls it lost.
WAIT = 60.0

# Real DDS on loopback only, in a domain of this run's own, so parallel runs never meet.
os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
os.environ.setdefault('ROS_DOMAIN_ID', str(random.Random(os.getpid()).randint(1, 100)))


# `make test-fast` (pytest -m fast): these modules, but for tests whose names start with one of
# the prefixes given. Together they run in under a minute on 2 cores: the layers and size
# limits, the world, data and generator, the models on small maps, the message conversion,
# the nodes' parameters, launch files and in-process nodes. Left to `make test`: the linters
# (`make lint`), training, RL, the shipped checkpoints' evaluations, the suite and studies,
# the demo's and colcon's processes.
FAST = {
    'test_layers': (),
    'test_code_limits': (),
    'test_world': (),
    'test_data': (),
    'test_generator': (),
    'test_augment': (),
    'test_noise': (),
    'test_allocator': (),
    'test_protocol': (),
    'test_models': (),
    'test_env': (),
    'test_grounder_api': (),
    'test_results': ('test_shipped_',),
    'test_results_merge': (),
    'test_ros_convert': (),
    'test_ros_parameters': (),
    'test_ros_config': (),
    'test_grounder_node': (),
    'test_grounder_orientation': (),
    'test_bags': (),
    'test_bag_recorder': (),
    'test_copyright': (),
    'test_natural_cases': (),
}


def pytest_collection_modifyitems(items):
    """Mark FAST's tests `fast`."""
    for item in items:
        left_out = FAST.get(item.path.stem)
        if left_out is not None and not item.name.startswith(left_out):
            item.add_marker(pytest.mark.fast)


@pytest.fixture(scope='session')
def data_dir() -> Path:
    if not (DATA / 'puddleworld' / 'local.p').is_file():
        pytest.skip(f'real data sets not found at {DATA} (set SPATIAL_GROUNDING_DATA)')
    return DATA


class RosGraph:
    """
    A fresh rclpy Context whose nodes spin in a background executor thread.

    Tests wait on what the nodes received with wait_for(); close() destroys every node added.
    """

    def __init__(self):
        import threading

        import rclpy
        from rclpy.executors import SingleThreadedExecutor

        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.nodes = []
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()

    def _spin(self):
        from rclpy.executors import ExternalShutdownException

        try:
            self.executor.spin()
        except ExternalShutdownException:
            pass

    def add(self, node):
        """Spin `node` (made with context=graph.context) and destroy it at the end."""
        self.nodes.append(node)
        self.executor.add_node(node)
        return node

    @staticmethod
    def wait_for(predicate, timeout: float = WAIT, interval: float = 0.01) -> bool:
        """
        Wait until `predicate()` holds; False only if it never does within `timeout`.

        An event-based wait: it returns as soon as the thing happens, so the timeout is
        generous (a busy shared machine can take seconds to discover a node) and only a thing
        that never happens fails a test. Never assert on how long something took.
        """
        import time

        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if predicate():
                return True
            time.sleep(interval)
        return bool(predicate())

    def close(self):
        self.executor.shutdown()
        self.thread.join(timeout=5)
        for node in self.nodes:
            node.destroy_node()
        self.context.try_shutdown()


@pytest.fixture
def ros_context():
    """Provide a RosGraph for one test (see RosGraph)."""
    pytest.importorskip('rclpy', reason='rclpy is not installed')
    graph = RosGraph()
    yield graph
    graph.close()


@pytest.fixture(scope='module')
def ros_module_context():
    """Provide a RosGraph shared by a test module, so its nodes start once."""
    pytest.importorskip('rclpy', reason='rclpy is not installed')
    graph = RosGraph()
    yield graph
    graph.close()
