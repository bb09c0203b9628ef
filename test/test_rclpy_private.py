# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The nodes use rclpy's public API only.

A private attribute of rclpy's classes (one leading underscore) may change in any release
without notice; this scans spatial_grounding_ros/ros/*.py for any access to one, by attribute
or by name in getattr/setattr/hasattr.
"""

import ast
from pathlib import Path

import pytest

pytest.importorskip('rclpy', reason='rclpy is not installed')

ROS = Path(__file__).resolve().parents[1] / 'spatial_grounding_ros' / 'ros'


def private(names) -> set[str]:
    return {n for n in names if n.startswith('_') and not n.startswith('__')}


@pytest.fixture(scope='module')
def rclpy_private() -> set[str]:
    """Single-underscore names of rclpy's Node, LifecycleNode and their entities, Context."""
    import rclpy
    from rclpy.client import Client
    from rclpy.context import Context
    from rclpy.lifecycle import LifecycleNode
    from rclpy.node import Node
    from rclpy.publisher import Publisher
    from rclpy.service import Service
    from rclpy.subscription import Subscription
    from std_msgs.msg import String
    from std_srvs.srv import Trigger

    context = Context()
    rclpy.init(context=context)
    try:
        node = Node('private_scan', context=context)
        lifecycle = LifecycleNode('private_scan_lifecycle', context=context)
        instances = [
            context,
            node,
            lifecycle,
            node.create_publisher(String, 'scan', 1),
            node.create_subscription(String, 'scan', lambda _: None, 1),
            node.create_service(Trigger, 'scan_srv', lambda _, r: r),
            node.create_client(Trigger, 'scan_srv'),
        ]
        names = set()
        for thing in instances + [Node, LifecycleNode, Publisher, Subscription, Service, Client]:
            names |= private(dir(thing))
        lifecycle.destroy_node()
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
    return names


def accesses(tree: ast.AST, names: set[str]):
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and node.attr in names:
            yield node.lineno, node.attr
        elif (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id in ('getattr', 'setattr', 'hasattr', 'delattr')
            and len(node.args) >= 2
            and isinstance(node.args[1], ast.Constant)
            and node.args[1].value in names
        ):
            yield node.lineno, node.args[1].value


def test_the_scan_knows_rclpys_private_names(rclpy_private):
    assert {'_parameter_overrides', '_state_machine', '_service_change_state'} <= rclpy_private
    tree = ast.parse('node._parameter_overrides\ngetattr(node, "_state_machine", None)\n')
    assert [name for _, name in accesses(tree, rclpy_private)] == [
        '_parameter_overrides',
        '_state_machine',
    ]


def test_no_private_rclpy_attribute_in_ros(rclpy_private):
    found = [
        f'{path.name}:{line}: {name}'
        for path in sorted(ROS.glob('*.py'))
        for line, name in accesses(ast.parse(path.read_text()), rclpy_private)
    ]
    assert not found, 'private rclpy attributes (use the public API):\n' + '\n'.join(found)
