# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
`ros2 run spatial_grounding_ros grounder` will work.

A colcon build of the package in a temporary workspace, the executable found through the ament
index exactly as `ros2 run` finds it, started as a process that joins the ROS graph as
`spatial_grounder`, reads its config from the install's share directory, and answers a request.
"""

import glob
import os
from pathlib import Path
import shutil
import subprocess
import sys

import pytest

pytest.importorskip('rclpy', reason='rclpy is not installed')
ament_packages = pytest.importorskip('ament_index_python.packages')

from grounder_helpers import interrupt, make_probe, unique_namespace  # noqa: E402, I100
from spatial_grounding_ros.data.generator import generate  # noqa: E402
from spatial_grounding_ros.grounder import DEFAULT_CHECKPOINT, Grounder  # noqa: E402
from spatial_grounding_ros.models.checkpoints import (  # noqa: E402
    load_checkpoint,
    resolve_checkpoint,
)
from spatial_grounding_ros.ros import convert  # noqa: E402

PACKAGE = 'spatial_grounding_ros'
REPO = Path(__file__).resolve().parents[1]
COLCON = Path(sys.executable).parent / 'colcon'
NAMESPACE = unique_namespace('colcon_test')
# what a source checkout holds besides the package: never part of a build
NOT_SOURCE = (
    '.venv',
    '.git',
    'build',
    'install',
    'log',
    'results',
    'out',
    'demo_out',
    '__pycache__',
    '*.egg-info',
    '.pytest_cache',
)


@pytest.fixture(scope='module')
def install_prefix(tmp_path_factory):
    if not COLCON.is_file():
        pytest.skip(f'colcon is not installed next to {sys.executable}')
    workspace = tmp_path_factory.mktemp('colcon_ws')
    shutil.copytree(REPO, workspace / 'src' / PACKAGE, ignore=shutil.ignore_patterns(*NOT_SOURCE))
    build = subprocess.run(
        [
            str(COLCON),
            'build',
            '--base-paths',
            'src',
            '--build-base',
            'build',
            '--install-base',
            'install',
        ],
        cwd=workspace,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert build.returncode == 0, build.stdout[-3000:] + build.stderr[-3000:]
    return workspace / 'install' / PACKAGE  # colcon's default isolated layout


@pytest.fixture
def ament_env(install_prefix, monkeypatch):
    """
    Return what sourcing install/setup.bash sets for this package (its dsv hooks).

    The prefix on AMENT_PREFIX_PATH, its site-packages on PYTHONPATH.
    """
    [site] = glob.glob(str(install_prefix / 'lib' / 'python3*' / 'site-packages'))
    for var, value in (('AMENT_PREFIX_PATH', str(install_prefix)), ('PYTHONPATH', site)):
        monkeypatch.setenv(var, os.pathsep.join(filter(None, [value, os.environ.get(var)])))
    return dict(os.environ)


def test_ament_index_finds_executables_and_share_files(install_prefix, ament_env):
    prefix = Path(ament_packages.get_package_prefix(PACKAGE))
    assert prefix == install_prefix
    for name in ('grounder', 'gridworld'):
        exe = prefix / 'lib' / PACKAGE / name
        assert exe.is_file() and os.access(exe, os.X_OK), exe
    share = Path(ament_packages.get_package_share_directory(PACKAGE))
    for name in INSTALLED:
        assert (share / name).is_file(), name


# what the share directory must hold, each a copy of the source file
INSTALLED = (
    'config/grounder.yaml',
    'config/gridworld.yaml',
    'config/entities_puddleworld.yaml',
    'config/entities_isi.yaml',
    'launch/grounder.launch.py',
    'launch/demo.launch.py',
    'launch/robot.launch.py',
    'config/entity_mapper.yaml',
    'config/entities_office.yaml',
    'rviz/spatial_grounding.rviz',
    'package.xml',
    'LICENSE',
)


def test_installed_files_are_the_checked_ones(install_prefix, ament_env):
    """
    Check that colcon installs the source launch, params and RViz files.

    The launch, params and RViz files colcon installs are the source files whose
    arguments, nodes, parameters and displays test_ros_config checks (that part needs no
    ROS launch); the installed params files load with rclpy's parser.
    """
    from rclpy.parameter import parameter_dict_from_yaml_file

    share = Path(ament_packages.get_package_share_directory(PACKAGE))
    for name in INSTALLED:
        assert (share / name).read_bytes() == (REPO / name).read_bytes(), name
    for name in ('grounder.launch.py', 'demo.launch.py', 'robot.launch.py'):
        compile((share / 'launch' / name).read_text(), name, 'exec')
    for name in ('grounder.yaml', 'gridworld.yaml'):
        assert parameter_dict_from_yaml_file(str(share / 'config' / name)), name


@pytest.mark.parametrize(
    'name, nodes', [('grounder.launch.py', 1), ('demo.launch.py', 3), ('robot.launch.py', 3)]
)
def test_launch_description_builds_with_ros_launch(install_prefix, ament_env, name, nodes):
    """
    What only ROS launch can show: the installed file builds a description holding its Nodes.

    `launch` and `launch_ros` are not on PyPI, so this skips in the venv and runs on a ROS 2 system
    (colcon test).
    """
    # launch.actions, not launch: this repository's launch/ folder imports as `launch`
    pytest.importorskip(
        'launch.actions',
        reason='ROS launch is not installed (not on PyPI); '
        "test_ros_config checks the file's arguments, node and parameters",
    )
    pytest.importorskip('launch_ros.actions', reason='launch_ros is not installed (not on PyPI)')
    share = Path(ament_packages.get_package_share_directory(PACKAGE))
    namespace = {}
    exec((share / 'launch' / name).read_text(), namespace)
    description = namespace['generate_launch_description']()
    assert sum(type(e).__name__ == 'Node' for e in description.entities) == nodes


def test_installed_grounder_joins_the_graph_and_answers(install_prefix, ament_env, ros_context):
    exe = Path(ament_packages.get_package_prefix(PACKAGE)) / 'lib' / PACKAGE / 'grounder'
    # PuddleWorld maps: the default table is the office one (the entity mapper's)
    table = 'entity_table:=entities_puddleworld.yaml'
    args = ['--ros-args', '-r', f'__ns:={NAMESPACE}', '-p', table]
    # the packaged defaults, packaged checkpoint included: a checkpoint that cannot load fails
    # here (and the node would exit with an error), never falls back to another model
    checkpoint = resolve_checkpoint(DEFAULT_CHECKPOINT)
    load_checkpoint(checkpoint)
    process = subprocess.Popen(
        [str(exe), *args],
        env=ament_env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        graph = ros_context
        probe = graph.add(make_probe(graph.context, NAMESPACE, f'{NAMESPACE}/spatial_grounder'))
        assert graph.wait_for(
            lambda: (
                ('spatial_grounder', NAMESPACE) in probe.get_node_names_and_namespaces()
                or process.poll() is not None
            ),
            timeout=45,
        )
        assert process.poll() is None, process.stdout.read()
        assert graph.wait_for(probe.connected)

        world = generate(1, seed=5, mode='global')
        grid, text = world.grids[0], world.instructions[0]
        message = probe.publish_map(grid)
        assert graph.wait_for(lambda: probe.holds(message))
        before = probe.counts()
        probe.publish_instruction(text)
        assert graph.wait_for(lambda: probe.new('goals', before))
        expected = Grounder.from_checkpoint(str(checkpoint)).ground(grid, text).goal
        position = probe.new('goals', before)[0].pose.position
        assert (position.x, position.y) == pytest.approx(
            convert.cell_centre(expected, convert.map_info(grid.shape))[:2]
        )
    finally:
        returncode, output = interrupt(process)
    assert returncode == 0, output
    # its config came from the colcon install, not from this source tree, and its model is
    # the packaged default of the install
    share = ament_packages.get_package_share_directory(PACKAGE)
    assert f'entity table {share}/config/entities_puddleworld.yaml' in output, output
    assert f'model {load_checkpoint(checkpoint).name} from {install_prefix}' in output, output
    assert f'/{checkpoint.name}, entity table' in output, output
