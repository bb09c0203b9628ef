# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Node parameters as a ROS user meets them, over real DDS.

The shipped params files apply under any namespace (the /**/<node> key), every parameter is
declared with a descriptor, set_parameters refuses bad values and read-only ones with a reason, and
an unknown name in a params file is a warning, not silence. (Start-up errors of the executables:
the console and gridworld tests.)
"""

import pytest
import yaml

pytest.importorskip('rclpy', reason='rclpy is not installed')

from grounder_helpers import unique_namespace  # noqa: E402, I100
from rcl_interfaces.msg import ParameterType  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.parameter import Parameter, parameter_value_to_python  # noqa: E402
from rclpy.parameter_client import AsyncParameterClient  # noqa: E402
from spatial_grounding_ros.ros import gridworld_node, grounder_node  # noqa: E402
from spatial_grounding_ros.ros.gridworld_node import GridWorldNode  # noqa: E402
from spatial_grounding_ros.ros.grounder_node import GrounderNode  # noqa: E402
from spatial_grounding_ros.ros.package_files import find_config  # noqa: E402


def shipped_copy(tmp_path, name: str, key: str | None = None, **changes):
    """
    config/<name> with `changes` to its values, written to tmp_path.

    Its node key as shipped (or `key`).
    """
    params = yaml.safe_load(find_config(name).read_text())
    [(shipped_key, section)] = params.items()
    section['ros__parameters'].update(changes)
    path = tmp_path / f'{key or "shipped"}_{name}'
    path.write_text(yaml.safe_dump({key or shipped_key: section}))
    return path


def remote_parameters(graph, node_name: str) -> AsyncParameterClient:
    """Return a parameter client of `node_name` on a node of its own (answers come over DDS)."""
    caller = graph.add(
        Node('parameter_caller', namespace=unique_namespace('caller'), context=graph.context)
    )
    client = AsyncParameterClient(caller, node_name)
    assert client.wait_for_services(timeout_sec=30), f'no parameter services of {node_name}'
    return client


def result(graph, future):
    assert graph.wait_for(future.done, timeout=30), 'no answer from the parameter service'
    return future.result()


def remote_values(graph, client, names):
    values = result(graph, client.get_parameters(names)).values
    return {n: parameter_value_to_python(v) for n, v in zip(names, values)}


def test_shipped_grounder_params_apply_under_a_namespace(ros_context, tmp_path):
    """
    Check that a namespaced grounder takes the shipped grounder.yaml.

    A grounder under /<run>/robot1 with the shipped grounder.yaml (its /**/spatial_grounder
    key, one value changed) has that value; the old `spatial_grounder:` key would not reach
    a namespaced node (the control).
    """
    graph = ros_context
    assert grounder_node.PARAMETERS[2].name == 'max_cells'
    assert grounder_node.PARAMETERS[2].default != 1234
    robot = unique_namespace('params') + '/robot1'
    path = shipped_copy(tmp_path, 'grounder.yaml', max_cells=1234, autostart=False)
    graph.add(
        GrounderNode(
            context=graph.context,
            namespace=robot,
            cli_args=['--ros-args', '--params-file', str(path)],
        )
    )
    client = remote_parameters(graph, f'{robot}/spatial_grounder')
    values = remote_values(graph, client, ['max_cells', 'autostart', 'checkpoint'])
    assert values == {'max_cells': 1234, 'autostart': False, 'checkpoint': 'pw_t-rnet-attn'}

    plain = shipped_copy(
        tmp_path, 'grounder.yaml', key='spatial_grounder', max_cells=1234, autostart=False
    )
    control = graph.add(
        GrounderNode(
            context=graph.context,
            namespace=robot + '_control',
            cli_args=['--ros-args', '--params-file', str(plain)],
        )
    )
    assert control.get_parameter('max_cells').value == 1048576


def test_shipped_gridworld_params_apply_under_a_namespace(ros_context, tmp_path):
    graph = ros_context
    robot = unique_namespace('params') + '/robot1'
    path = shipped_copy(tmp_path, 'gridworld.yaml', episodes=3, seed=5, step_period=0.25)
    graph.add(
        GridWorldNode(
            context=graph.context,
            namespace=robot,
            cli_args=['--ros-args', '--params-file', str(path)],
        )
    )
    client = remote_parameters(graph, f'{robot}/gridworld')
    assert remote_values(graph, client, ['episodes', 'seed', 'step_period']) == {
        'episodes': 3,
        'seed': 5,
        'step_period': 0.25,
    }


def test_set_parameters_refuses_bad_and_read_only_values_with_a_reason(ros_context):
    graph = ros_context
    namespace = unique_namespace('set_params')
    grounder = graph.add(
        GrounderNode(
            context=graph.context,
            namespace=namespace,
            parameter_overrides=[Parameter('autostart', value=False)],
        )
    )
    client = remote_parameters(graph, f'{namespace}/spatial_grounder')
    refused = {  # the examples first: each used to succeed and change nothing
        'checkpoint': ('other.pt', 'read-only'),
        'torch_threads': (-3, 'read-only'),
        'max_instruction_chars': (0, 'max_instruction_chars'),
        'max_cells': (-5, 'max_cells'),
        'value_map_encoding': ('heat', 'must be one of display, cost'),
        'default_frame_id': ('', 'must not be empty'),
        'reground_on_map_change': ('yes', 'Wrong parameter type'),
    }
    for name, (value, reason) in refused.items():
        before = grounder.get_parameter(name).value
        [answer] = result(graph, client.set_parameters([Parameter(name, value=value)])).results
        assert not answer.successful and reason in answer.reason, (name, answer.reason)
        assert grounder.get_parameter(name).value == before
    for name, value in (
        ('max_cells', 100),
        ('value_map_encoding', 'cost'),
        ('default_frame_id', 'odom'),
        ('reground_on_map_change', True),
    ):
        [answer] = result(graph, client.set_parameters([Parameter(name, value=value)])).results
        assert answer.successful, (name, answer.reason)
        assert grounder.get_parameter(name).value == value


@pytest.mark.parametrize('module', [grounder_node, gridworld_node])
def test_every_parameter_is_described(ros_context, module):
    """
    Check what `ros2 param describe` shows.

    A description, the type, read_only for what only start-up sets, and the range of each number,
    as the node declares them.
    """
    graph = ros_context
    namespace = unique_namespace('describe')
    if module is grounder_node:
        node = graph.add(
            GrounderNode(
                context=graph.context,
                namespace=namespace,
                parameter_overrides=[Parameter('autostart', value=False)],
            )
        )
    else:
        node = graph.add(
            GridWorldNode(
                context=graph.context,
                namespace=namespace,
                parameter_overrides=[Parameter('episodes', value=2)],
            )
        )
    client = remote_parameters(graph, node.get_fully_qualified_name())
    names = [p.name for p in module.PARAMETERS]
    described = result(graph, client.describe_parameters(names)).descriptors
    types = {
        bool: ParameterType.PARAMETER_BOOL,
        int: ParameterType.PARAMETER_INTEGER,
        float: ParameterType.PARAMETER_DOUBLE,
        str: ParameterType.PARAMETER_STRING,
    }
    for spec, descriptor in zip(module.PARAMETERS, described):
        assert descriptor.name == spec.name and len(descriptor.description) > 10, spec.name
        assert descriptor.type == types[spec.type] and descriptor.read_only == spec.read_only
        if spec.low is not None:
            [bounds] = descriptor.integer_range or descriptor.floating_point_range
            assert (bounds.from_value, bounds.to_value) == (spec.low, spec.high), spec.name
        if spec.choices:
            assert descriptor.additional_constraints == 'one of ' + ', '.join(spec.choices)
    listed = result(graph, client.list_parameters([], 0)).result.names
    assert set(names) <= set(listed)


def test_an_unknown_name_in_a_params_file_is_a_warning(ros_context, tmp_path, capfd):
    graph = ros_context
    path = shipped_copy(tmp_path, 'grounder.yaml', autostart=False, max_cell=10)
    graph.add(
        GrounderNode(
            context=graph.context,
            namespace=unique_namespace('unknown'),
            cli_args=['--ros-args', '--params-file', str(path)],
        )
    )
    err = capfd.readouterr().err
    [line] = [line for line in err.splitlines() if 'unknown parameter' in line]
    assert '[WARN]' in line and 'ignoring unknown parameter(s) max_cell ' in line, line
    assert 'max_cells' in line  # it names the real ones
