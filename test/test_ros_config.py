"""config/: the entity tables are the core's, grounder.yaml is a ROS params file holding every
parameter of the node, and config files are found from a path or by name."""
from pathlib import Path

import pytest
import yaml

from spatial_grounding_ros.entities import ISI, PUDDLEWORLD, EntityTable
from spatial_grounding_ros.ros.package_files import find_config

REPO = Path(__file__).resolve().parents[1]
GROUNDER_PARAMETERS = {
    "checkpoint", "entity_table", "entity_map_topic", "instruction_topic", "value_map_topic",
    "value_map_raw_topic", "relation_map_topic", "goal_pose_topic", "diagnostics_topic",
    "max_cells", "max_instruction_chars", "reground_on_map_change", "torch_threads",
    "default_frame_id"}


@pytest.mark.parametrize("name, table", [("entities_puddleworld.yaml", PUDDLEWORLD),
                                         ("entities_isi.yaml", ISI)])
def test_entity_tables_are_the_core_tables(name, table):
    assert EntityTable.from_yaml(REPO / "config" / name) == table


def test_grounder_params_file_holds_every_parameter():
    params = yaml.safe_load((REPO / "config" / "grounder.yaml").read_text())
    assert set(params) == {"spatial_grounder"}
    values = params["spatial_grounder"]["ros__parameters"]
    assert set(values) == GROUNDER_PARAMETERS
    assert values["checkpoint"] == "pw_t-rnet-attn"
    assert EntityTable.from_yaml(find_config(values["entity_table"])) == PUDDLEWORLD


def test_find_config_by_path_and_by_name(tmp_path):
    own = tmp_path / "mine.yaml"
    own.write_text("x: 1\n")
    assert find_config(own) == own
    assert find_config("grounder.yaml").read_text() == (REPO / "config" /
                                                        "grounder.yaml").read_text()
    with pytest.raises(FileNotFoundError, match="no_such.yaml: config file not found"):
        find_config("no_such.yaml")


# --- launch/grounder.launch.py, read as source: `launch` is not on PyPI, so it cannot be
# imported here (test_grounder_colcon builds the description where launch is installed)

LAUNCH_FILE = REPO / "launch" / "grounder.launch.py"


def launch_calls() -> dict:
    """The launch file's generate_launch_description() as plain data, from its syntax tree:
    every call becomes {"call": name, "args": [...], **keywords}, names resolve to their
    module-level or local assignments, os.path.join to a list of its parts."""
    import ast

    tree = ast.parse(LAUNCH_FILE.read_text(), str(LAUNCH_FILE))
    names = {t.id: node.value for node in tree.body if isinstance(node, ast.Assign)
             for t in node.targets}
    [function] = [n for n in tree.body if isinstance(n, ast.FunctionDef)
                  and n.name == "generate_launch_description"]
    names.update({t.id: node.value for node in function.body if isinstance(node, ast.Assign)
                  for t in node.targets})

    def value(node):
        if isinstance(node, ast.Constant):
            return node.value
        if isinstance(node, ast.Name):
            return value(names[node.id])
        if isinstance(node, ast.List):
            return [value(e) for e in node.elts]
        if isinstance(node, ast.Call):
            func = ast.unparse(node.func)
            if func == "os.path.join":
                return {"join": [value(a) for a in node.args]}
            return {"call": func, "args": [value(a) for a in node.args],
                    **{k.arg: value(k.value) for k in node.keywords}}
        raise AssertionError(f"unexpected launch file syntax: {ast.unparse(node)}")

    [ret] = [n for n in function.body if isinstance(n, ast.Return)]
    return value(ret.value)


def test_launch_file_declares_its_arguments_and_starts_the_grounder():
    """`ros2 launch spatial_grounding_ros grounder.launch.py params_file:=... namespace:=...`:
    the two arguments exist with the documented defaults (the installed grounder.yaml, no
    namespace), the node is our `grounder` executable named as its parameters file expects,
    and it takes the namespace and the parameters file from those arguments."""
    description = launch_calls()
    assert description["call"] == "LaunchDescription"
    [entities] = description["args"]
    arguments = {e["args"][0]: e for e in entities if e["call"] == "DeclareLaunchArgument"}
    [node] = [e for e in entities if e["call"] == "Node"]
    assert len(entities) == len(arguments) + 1
    assert set(arguments) == {"params_file", "namespace"}
    assert arguments["namespace"]["default_value"] == ""
    default = arguments["params_file"]["default_value"]["join"]
    assert default[0] == {"call": "get_package_share_directory", "args": ["spatial_grounding_ros"]}
    assert default[1:] == ["config", "grounder.yaml"] and (REPO / "config" / "grounder.yaml").is_file()
    # the executable is a console script of the package (colcon installs it into lib/<package>)
    assert node["package"] == "spatial_grounding_ros" and node["executable"] == "grounder"
    assert "grounder = spatial_grounding_ros.ros.grounder_node:main" in (REPO / "setup.py").read_text()
    # the parameters file's section is the node's name, so its parameters reach the node
    params = yaml.safe_load((REPO / "config" / "grounder.yaml").read_text())
    assert node["name"] == "spatial_grounder" and set(params) == {node["name"]}
    assert node["namespace"] == {"call": "LaunchConfiguration", "args": ["namespace"]}
    assert node["parameters"] == [{"call": "LaunchConfiguration", "args": ["params_file"]}]


def test_readme_launch_line_uses_the_declared_arguments():
    """The README's `ros2 launch` line passes only arguments the launch file declares."""
    import re

    declared = {e["args"][0] for e in launch_calls()["args"][0]
                if e["call"] == "DeclareLaunchArgument"}
    lines = [line for line in (REPO / "README.md").read_text().splitlines()
             if line.startswith("ros2 launch spatial_grounding_ros grounder.launch.py")]
    assert lines
    for line in lines:
        used = set(re.findall(r"(\w+):=", line))
        assert used and used <= declared, line
