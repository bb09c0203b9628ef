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
