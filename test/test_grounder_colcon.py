"""`ros2 run spatial_grounding_ros grounder` will work: a colcon build of the package in a
temporary workspace, the executable found through the ament index exactly as `ros2 run`
finds it, started as a process that joins the ROS graph as `spatial_grounder`, reads its
config from the install's share directory, and answers a request."""
import glob
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="rclpy is not installed")
ament_packages = pytest.importorskip("ament_index_python.packages")

from grounder_helpers import interrupt, make_probe, random_checkpoint  # noqa: E402

from spatial_grounding_ros.checkpoints import load_checkpoint, resolve_checkpoint  # noqa: E402
from spatial_grounding_ros.generator import generate  # noqa: E402
from spatial_grounding_ros.grounder import DEFAULT_CHECKPOINT, Grounder  # noqa: E402
from spatial_grounding_ros.ros import convert  # noqa: E402

PACKAGE = "spatial_grounding_ros"
REPO = Path(__file__).resolve().parents[1]
COLCON = Path(sys.executable).parent / "colcon"
NAMESPACE = "/colcon_test"
# what a source checkout holds besides the package: never part of a build
NOT_SOURCE = (".venv", ".git", "build", "install", "log", "results", "out", "demo_out",
              "__pycache__", "*.egg-info", ".pytest_cache")


@pytest.fixture(scope="module")
def install_prefix(tmp_path_factory):
    if not COLCON.is_file():
        pytest.skip(f"colcon is not installed next to {sys.executable}")
    workspace = tmp_path_factory.mktemp("colcon_ws")
    shutil.copytree(REPO, workspace / "src" / PACKAGE, ignore=shutil.ignore_patterns(*NOT_SOURCE))
    build = subprocess.run(
        [str(COLCON), "build", "--base-paths", "src", "--build-base", "build",
         "--install-base", "install"],
        cwd=workspace, capture_output=True, text=True, timeout=120)
    assert build.returncode == 0, build.stdout[-3000:] + build.stderr[-3000:]
    return workspace / "install" / PACKAGE  # colcon's default isolated layout


@pytest.fixture
def ament_env(install_prefix, monkeypatch):
    """What sourcing install/setup.bash sets for this package (its dsv hooks): the prefix on
    AMENT_PREFIX_PATH, its site-packages on PYTHONPATH."""
    [site] = glob.glob(str(install_prefix / "lib" / "python3*" / "site-packages"))
    for var, value in (("AMENT_PREFIX_PATH", str(install_prefix)), ("PYTHONPATH", site)):
        monkeypatch.setenv(var, os.pathsep.join(filter(None, [value, os.environ.get(var)])))
    return dict(os.environ)


def test_ament_index_finds_executables_and_share_files(install_prefix, ament_env):
    prefix = Path(ament_packages.get_package_prefix(PACKAGE))
    assert prefix == install_prefix
    for name in ("grounder", "gridworld"):
        exe = prefix / "lib" / PACKAGE / name
        assert exe.is_file() and os.access(exe, os.X_OK), exe
    share = Path(ament_packages.get_package_share_directory(PACKAGE))
    for name in ("config/grounder.yaml", "config/entities_puddleworld.yaml",
                 "config/entities_isi.yaml", "launch/grounder.launch.py", "package.xml"):
        assert (share / name).is_file(), name


def test_launch_file_describes_the_grounder(install_prefix, ament_env):
    share = Path(ament_packages.get_package_share_directory(PACKAGE))
    source = (share / "launch" / "grounder.launch.py").read_text()
    compile(source, "grounder.launch.py", "exec")  # syntax, even where launch is absent
    for part in ('executable="grounder"', 'name="spatial_grounder"', '"grounder.yaml"'):
        assert part in source
    # launch.actions, not launch: this repository's launch/ folder imports as `launch`
    pytest.importorskip("launch.actions", reason="ROS launch is not installed (not on PyPI)")
    pytest.importorskip("launch_ros.actions", reason="launch_ros is not installed")
    namespace = {}
    exec(source, namespace)
    description = namespace["generate_launch_description"]()
    assert any(type(e).__name__ == "Node" for e in description.entities)


def test_installed_grounder_joins_the_graph_and_answers(install_prefix, ament_env,
                                                        ros_context, tmp_path):
    exe = Path(ament_packages.get_package_prefix(PACKAGE)) / "lib" / PACKAGE / "grounder"
    args = ["--ros-args", "-r", f"__ns:={NAMESPACE}"]
    try:  # the packaged defaults when there is a checkpoint; else a test checkpoint
        checkpoint = resolve_checkpoint(DEFAULT_CHECKPOINT)
        load_checkpoint(checkpoint)
    except (FileNotFoundError, ValueError):
        checkpoint = random_checkpoint(tmp_path / "random.pt")
        args += ["-p", f"checkpoint:={checkpoint}"]
    process = subprocess.Popen([str(exe), *args], env=ament_env, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True)
    try:
        graph = ros_context
        probe = graph.add(make_probe(graph.context, NAMESPACE, f"{NAMESPACE}/spatial_grounder"))
        assert graph.wait_for(
            lambda: ("spatial_grounder", NAMESPACE) in probe.get_node_names_and_namespaces()
            or process.poll() is not None, timeout=45)
        assert process.poll() is None, process.stdout.read()
        assert graph.wait_for(probe.connected, timeout=15)

        world = generate(1, seed=5, mode="global")
        grid, text = world.grids[0], world.instructions[0]
        probe.publish_map(grid)
        before = probe.counts()
        probe.publish_instruction(text)
        assert graph.wait_for(lambda: probe.new("goals", before), timeout=15)
        expected = Grounder.from_checkpoint(str(checkpoint)).ground(grid, text).goal
        position = probe.new("goals", before)[0].pose.position
        assert (position.x, position.y) == pytest.approx(
            convert.cell_centre(expected, convert.map_info(grid.shape))[:2])
    finally:
        returncode, output = interrupt(process)
    assert returncode == 0, output
    # its config came from the colcon install, not from this source tree
    share = ament_packages.get_package_share_directory(PACKAGE)
    assert f"entity table {share}/config/entities_puddleworld.yaml" in output, output
