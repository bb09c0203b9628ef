# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
config/, launch/ and rviz/ checked without ROS launch or RViz (not on PyPI).

The entity tables are the core's; each shipped params file holds every parameter its node declares,
with the declared default, keyed so that it applies in any namespace, and loads with rclpy's
parser; the launch files declare the arguments the README uses and start our nodes with those
params files; the RViz config shows our topics. Config files are found from a path or by name.
"""

import ast
from pathlib import Path
import re

import pytest
from spatial_grounding_ros.core.entities import EntityTable, ISI, PUDDLEWORLD
from spatial_grounding_ros.ros.package_files import find_config
import yaml

REPO = Path(__file__).resolve().parents[1]
SHARE = {'call': 'get_package_share_directory', 'args': ['spatial_grounding_ros']}


def lc(name: str) -> dict:
    """Return a LaunchConfiguration(name), as launch_calls() reads it."""
    return {'call': 'LaunchConfiguration', 'args': [name]}


def node_parameters(node_module: str):
    """(node name, its declared parameters) of grounder_node or gridworld_node."""
    pytest.importorskip('rclpy', reason='rclpy is not installed')
    import importlib

    module = importlib.import_module(f'spatial_grounding_ros.ros.{node_module}')
    return module.NODE_NAME, module.PARAMETERS


@pytest.mark.parametrize(
    'name, table', [('entities_puddleworld.yaml', PUDDLEWORLD), ('entities_isi.yaml', ISI)]
)
def test_entity_tables_are_the_core_tables(name, table):
    assert EntityTable.from_yaml(REPO / 'config' / name) == table


@pytest.mark.parametrize(
    'file, node_module', [('grounder.yaml', 'grounder_node'), ('gridworld.yaml', 'gridworld_node')]
)
def test_params_file_holds_every_declared_parameter_for_any_namespace(file, node_module):
    """
    Check that the shipped file is the node's declared defaults.

    The shipped file is the node's declared defaults, keyed /**/<node> so that it applies
    under -r __ns:=/robot1 too (test_ros_parameters starts nodes that way), and rclpy's own
    parser reads it to the same values.
    """
    from rclpy.parameter import parameter_dict_from_yaml_file, parameter_value_to_python

    name, parameters = node_parameters(node_module)
    params = yaml.safe_load((REPO / 'config' / file).read_text())
    assert set(params) == {f'/**/{name}'}
    values = params[f'/**/{name}']['ros__parameters']
    assert values == {p.name: p.default for p in parameters}
    assert [type(values[p.name]) for p in parameters] == [p.type for p in parameters]
    parsed = parameter_dict_from_yaml_file(str(REPO / 'config' / file))
    assert {k: parameter_value_to_python(v.value) for k, v in parsed.items()} == values


def test_grounder_defaults_find_their_files():
    _, parameters = node_parameters('grounder_node')
    defaults = {p.name: p.default for p in parameters}
    assert defaults['checkpoint'] == 'pw_t-rnet-attn'
    # the entity mapper's table: the two nodes work together as they start (issue 42)
    from spatial_grounding_ros.ros.entity_mapper_node import PARAMETERS as MAPPER

    mapper = {p.name: p.default for p in MAPPER}
    assert defaults['entity_table'] == mapper['entity_table'] == 'entities_office.yaml'
    assert EntityTable.from_yaml(find_config(defaults['entity_table'])).domain == 'office'


def test_find_config_by_path_and_by_name(tmp_path):
    own = tmp_path / 'mine.yaml'
    own.write_text('x: 1\n')
    assert find_config(own) == own
    assert (
        find_config('grounder.yaml').read_text() == (REPO / 'config' / 'grounder.yaml').read_text()
    )
    with pytest.raises(FileNotFoundError, match='no_such.yaml: config file not found'):
        find_config('no_such.yaml')


# --- launch/*.launch.py, read as source: `launch` is not on PyPI, so they cannot be imported
# here (test_grounder_colcon builds the descriptions where ROS launch is installed)


def launch_calls(name: str) -> dict:
    """
    Return a launch file's generate_launch_description() as plain data, from its syntax tree.

    Every call becomes {'call': name, 'args': [...], **keywords}, names resolve to their
    module-level or local assignments, os.path.join to {'join': [parts]}, dicts to dicts.
    """
    path = REPO / 'launch' / name
    tree = ast.parse(path.read_text(), str(path))
    names = {
        t.id: node.value
        for node in tree.body
        if isinstance(node, ast.Assign)
        for t in node.targets
    }
    [function] = [
        n
        for n in tree.body
        if isinstance(n, ast.FunctionDef) and n.name == 'generate_launch_description'
    ]
    names.update(
        {
            t.id: node.value
            for node in function.body
            if isinstance(node, ast.Assign)
            for t in node.targets
        }
    )

    def value(node):
        if isinstance(node, ast.Constant):
            return node.value
        if isinstance(node, ast.Name):
            return value(names[node.id])
        if isinstance(node, (ast.List, ast.Tuple)):
            return [value(e) for e in node.elts]
        if isinstance(node, ast.Dict):
            out = {}
            for k, v in zip(node.keys, node.values):
                out.update(value(v) if k is None else {value(k): value(v)})
            return out
        if isinstance(node, ast.Call):
            func = ast.unparse(node.func)
            if func == 'os.path.join':
                return {'join': [value(a) for a in node.args]}
            return {
                'call': func,
                'args': [value(a) for a in node.args],
                **{k.arg: value(k.value) for k in node.keywords},
            }
        raise AssertionError(f'unexpected launch file syntax: {ast.unparse(node)}')

    [ret] = [n for n in function.body if isinstance(n, ast.Return)]
    return value(ret.value)


def launch_parts(name: str):
    """({argument: DeclareLaunchArgument call}, [Node calls]) of a launch file."""
    description = launch_calls(name)
    assert description['call'] == 'LaunchDescription'
    [entities] = description['args']
    arguments = {e['args'][0]: e for e in entities if e['call'] == 'DeclareLaunchArgument'}
    nodes = [e for e in entities if e['call'] == 'Node']
    assert len(entities) == len(arguments) + len(nodes)
    assert all(a.get('description') for a in arguments.values())
    return arguments, nodes


def check_our_node(node: dict, executable: str, params_argument: str) -> dict:
    """
    Return a Node of our package.

    The console script, the name its params file is keyed by, the namespace argument, the params
    file then the launch-argument overrides (names the node declares), and the log level. Returns
    the overrides.
    """
    name, parameters = node_parameters(f'{executable}_node')
    assert node['package'] == 'spatial_grounding_ros' and node['executable'] == executable
    assert (
        f'{executable} = spatial_grounding_ros.ros.{executable}_node:main'
        in (REPO / 'setup.py').read_text()
    )
    params = yaml.safe_load(find_config(f'{executable}.yaml').read_text())
    assert node['name'] == name and set(params) == {f'/**/{name}'}
    assert node['namespace'] == lc('namespace')
    params_file, overrides = node['parameters']
    assert params_file == lc(params_argument)
    declared = {p.name for p in parameters} | {'use_sim_time'}
    assert set(overrides) <= declared and overrides['use_sim_time'] == lc('use_sim_time')
    assert node['arguments'] == ['--ros-args', '--log-level', lc('log_level')]
    return overrides


def check_default_params_file(argument: dict, file: str) -> None:
    assert argument['default_value'] == {'join': [SHARE, 'config', file]}
    assert (REPO / 'config' / file).is_file()


def test_grounder_launch_file_arguments_and_node():
    """
    `ros2 launch spatial_grounding_ros grounder.launch.py namespace:=...

    use_sim_time:=... log_level:=... autostart:=... params_file:=...` reach the grounder.
    """
    arguments, [node] = launch_parts('grounder.launch.py')
    assert set(arguments) == {'namespace', 'params_file', 'use_sim_time', 'autostart', 'log_level'}
    defaults = {k: a['default_value'] for k, a in arguments.items() if k != 'params_file'}
    assert defaults == {
        'namespace': '',
        'use_sim_time': 'false',
        'autostart': 'true',
        'log_level': 'info',
    }
    check_default_params_file(arguments['params_file'], 'grounder.yaml')
    overrides = check_our_node(node, 'grounder', 'params_file')
    assert overrides == {'use_sim_time': lc('use_sim_time'), 'autostart': lc('autostart')}


def test_demo_launch_file_starts_gridworld_grounder_and_rviz_on_request():
    arguments, nodes = launch_parts('demo.launch.py')
    assert set(arguments) == {
        'namespace',
        'grounder_params_file',
        'gridworld_params_file',
        'use_sim_time',
        'log_level',
        'rviz',
    }
    assert arguments['rviz']['default_value'] == 'false'
    check_default_params_file(arguments['grounder_params_file'], 'grounder.yaml')
    check_default_params_file(arguments['gridworld_params_file'], 'gridworld.yaml')
    grounder, gridworld, rviz = nodes
    check_our_node(grounder, 'grounder', 'grounder_params_file')
    overrides = check_our_node(gridworld, 'gridworld', 'gridworld_params_file')
    # the first episode waits for the grounder's instruction subscription
    assert overrides['start_after_subscribers'] == 1
    assert 'condition' not in grounder and 'condition' not in gridworld
    assert (rviz['package'], rviz['executable']) == ('rviz2', 'rviz2')
    assert rviz['condition'] == {'call': 'IfCondition', 'args': [lc('rviz')]}
    assert rviz['namespace'] == lc('namespace')  # its relative topics follow the nodes
    [flag, config] = rviz['arguments']
    assert flag == '-d' and config == {'join': [SHARE, 'rviz', 'spatial_grounding.rviz']}
    assert (REPO / 'rviz' / 'spatial_grounding.rviz').is_file()


def test_robot_launch_file_starts_mapper_and_grounder_with_one_entity_table():
    """
    `ros2 launch spatial_grounding_ros robot.launch.py entity_table:=...` (issue 42).

    The entity mapper and the grounder, each with its params file and then the one
    entity_table, use_sim_time and autostart; the mapper's map topic remapped; RViz on request.
    """
    arguments, nodes = launch_parts('robot.launch.py')
    assert set(arguments) == {
        'namespace',
        'entity_table',
        'map_topic',
        'grounder_params_file',
        'mapper_params_file',
        'use_sim_time',
        'autostart',
        'log_level',
        'rviz',
    }
    assert arguments['entity_table']['default_value'] == 'entities_office.yaml'
    assert find_config(arguments['entity_table']['default_value']).is_file()
    check_default_params_file(arguments['grounder_params_file'], 'grounder.yaml')
    check_default_params_file(arguments['mapper_params_file'], 'entity_mapper.yaml')
    mapper, grounder, rviz = nodes
    shared = {
        'use_sim_time': lc('use_sim_time'),
        'autostart': lc('autostart'),
        'entity_table': lc('entity_table'),
    }
    assert check_our_node(mapper, 'entity_mapper', 'mapper_params_file') == shared
    assert check_our_node(grounder, 'grounder', 'grounder_params_file') == shared
    assert mapper['remappings'] == [['map', lc('map_topic')]]
    assert 'condition' not in mapper and 'condition' not in grounder
    assert (rviz['package'], rviz['executable']) == ('rviz2', 'rviz2')
    assert rviz['condition'] == {'call': 'IfCondition', 'args': [lc('rviz')]}
    assert rviz['namespace'] == lc('namespace')


def test_robot_launch_file_builds_its_description_where_ros_launch_is_installed():
    """Import the file and build its description (skips where `launch` is not installed)."""
    import importlib.util

    pytest.importorskip('launch.actions', reason='ROS launch is not installed (not on PyPI)')
    pytest.importorskip('launch_ros.actions', reason='launch_ros is not installed (not on PyPI)')
    path = REPO / 'launch' / 'robot.launch.py'
    spec = importlib.util.spec_from_file_location('robot_launch', path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    description = module.generate_launch_description()
    executables = [getattr(e, 'node_executable', None) for e in description.entities]
    assert 'entity_mapper' in executables and 'grounder' in executables


def test_readme_launch_lines_use_the_declared_arguments():
    """
    Check the documentation's `ros2 launch` lines against the launch files' arguments.

    Every `ros2 launch spatial_grounding_ros X.launch.py ...` line of the README and the docs/
    pages passes only arguments X declares (and the README shows both launch files).
    """
    readme = (REPO / 'README.md').read_text()
    pages = [readme, *(p.read_text() for p in sorted((REPO / 'docs').glob('*.md')))]
    assert {'robot.launch.py', 'grounder.launch.py', 'demo.launch.py'} <= set(
        re.findall(r'ros2 launch spatial_grounding_ros (\S+\.launch\.py)', readme)
    )
    seen = set()
    for line in '\n'.join(pages).splitlines():
        match = re.match(r'ros2 launch spatial_grounding_ros (\S+\.launch\.py)(.*)', line)
        if not match:
            continue
        file, rest = match.groups()
        seen.add(file)
        declared = set(launch_parts(file)[0])
        used = set(re.findall(r'(\w+):=', rest))
        assert used <= declared, line
    assert seen == {'robot.launch.py', 'grounder.launch.py', 'demo.launch.py'}


# --- rviz/spatial_grounding.rviz


def test_rviz_config_shows_the_maps_goal_agent_and_landmarks_on_relative_topics():
    config = yaml.safe_load((REPO / 'rviz' / 'spatial_grounding.rviz').read_text())
    manager = config['Visualization Manager']
    assert manager['Global Options']['Fixed Frame'] == 'map'
    displays = {d['Topic']['Value']: d for d in manager['Displays'] if 'Topic' in d}
    assert set(displays) == {
        'entity_map', 'value_map', 'relation_map', 'goal_pose', 'agent_pose', 'landmarks'
    }
    # the entity_mapper's input: the named landmarks as markers
    assert displays['landmarks']['Class'] == 'rviz_default_plugins/MarkerArray'
    for topic in ('entity_map', 'value_map', 'relation_map'):
        d = displays[topic]
        assert d['Class'] == 'rviz_default_plugins/Map'
        # the publishers are transient local: a volatile display would miss a held map
        assert d['Topic']['Durability Policy'] == 'Transient Local'
        assert d['Topic']['Reliability Policy'] == 'Reliable'
    assert displays['value_map']['Color Scheme'] == 'costmap'
    for topic in ('goal_pose', 'agent_pose'):
        assert displays[topic]['Class'] == 'rviz_default_plugins/Pose'
    [goal_tool] = [t for t in manager['Tools'] if t['Class'] == 'rviz_default_plugins/SetGoal']
    assert goal_tool['Topic']['Value'] == 'goal_pose'


# --- package.xml


# import name -> its package.xml key, for what the package imports outside the standard library
ROSDEP_KEYS = {
    'numpy': 'python3-numpy',
    'yaml': 'python3-yaml',
    'matplotlib': 'python3-matplotlib',
    'tqdm': 'python3-tqdm',
    'torch': 'python3-torch',
    'gymnasium': 'python3-gymnasium-pip',
    'rosbags': 'python3-rosbags-pip',
    'rapidfuzz': 'python3-rapidfuzz',
    'text_to_num': 'python3-text2num-pip',
    'symspellpy': 'python3-symspellpy-pip',
}


def test_package_xml_declares_every_imported_package():
    """Every third-party module imported under spatial_grounding_ros/ is a package.xml depend."""
    import sys
    import xml.etree.ElementTree as ElementTree

    root = ElementTree.parse(REPO / 'package.xml').getroot()
    depends = {e.text for e in root if e.tag in ('depend', 'exec_depend')}
    tests = {e.text for e in root if e.tag == 'test_depend'}
    imported = set()
    for path in (REPO / 'spatial_grounding_ros').rglob('*.py'):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                imported |= {a.name.split('.')[0] for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                imported.add(node.module.split('.')[0])
    third_party = imported - set(sys.stdlib_module_names) - {'spatial_grounding_ros'}
    missing = sorted(m for m in third_party if ROSDEP_KEYS.get(m, m) not in depends)
    assert not missing, f'package.xml lacks exec_depends for {missing}'
    assert {'ament_copyright', 'ament_flake8', 'ament_pep257', 'python3-pytest'} <= tests
    assert 'rviz2' in depends  # demo.launch.py's rviz:=true
