"""eval-bag on a bag written by another tool (rosbags directly, standard message types
only) and bad input: missing, non-bag, truncated, bag without the needed topics."""
import json

import numpy as np
import pytest

from spatial_grounding_ros import cli, world
from spatial_grounding_ros.bags import BagWriter, evaluate_bag, typestore

STORE = typestore()
T = STORE.types


def header(frame="map"):
    return T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=0, nanosec=0),
                                    frame_id=frame)


def pose_at(cell, height=10, resolution=0.5):
    """PoseStamped at the centre of data-set cell (row, col) of a map at origin (0, 0)."""
    P = T["geometry_msgs/msg/Pose"]
    point = T["geometry_msgs/msg/Point"](x=(cell[1] + 0.5) * resolution,
                                         y=(height - 1 - cell[0] + 0.5) * resolution, z=0.0)
    q = T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)
    return T["geometry_msgs/msg/PoseStamped"](header=header(), pose=P(position=point, orientation=q))


def occupancy(grid, resolution=0.5):
    h, w = grid.shape
    P = T["geometry_msgs/msg/Pose"]
    origin = P(position=T["geometry_msgs/msg/Point"](x=0.0, y=0.0, z=0.0),
               orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0))
    info = T["nav_msgs/msg/MapMetaData"](map_load_time=T["builtin_interfaces/msg/Time"](sec=0, nanosec=0),
                                         resolution=resolution, width=w, height=h, origin=origin)
    return T["nav_msgs/msg/OccupancyGrid"](header=header(), info=info,
                                           data=grid[::-1].astype(np.int8).reshape(-1))


def multiarray(values):
    values = np.asarray(values, np.float32)[::-1]
    h, w = values.shape
    D = T["std_msgs/msg/MultiArrayDimension"]
    layout = T["std_msgs/msg/MultiArrayLayout"](dim=[D(label="height", size=h, stride=h * w),
                                                     D(label="width", size=w, stride=w)],
                                                data_offset=0)
    return T["std_msgs/msg/Float32MultiArray"](layout=layout, data=values.reshape(-1))


def write_bag(path, episodes, with_values=False, skip=()):
    """episodes: (instruction, answered cell, true cell); gridworld order: truth, then
    instruction, then goal (and value map)."""
    grid = np.zeros((10, 10), np.int64)
    t = 1
    with BagWriter(path) as bag:
        if "map" not in skip:
            bag.write_message("/entity_map", "nav_msgs/msg/OccupancyGrid", t, occupancy(grid))
        for text, answer, truth in episodes:
            rewards, terminal = world.reward_map(np.zeros((10, 10), bool), truth)
            values = world.value_iteration(rewards, terminal)
            t += 10
            bag.write_message("/true_goal", "geometry_msgs/msg/PoseStamped", t, pose_at(truth))
            if with_values:
                bag.write_message("/true_value_map", "std_msgs/msg/Float32MultiArray", t + 1,
                                  multiarray(values))
                bag.write_message("/true_reward_map", "std_msgs/msg/Float32MultiArray", t + 1,
                                  multiarray(rewards))
            bag.write_message("/instruction", "std_msgs/msg/String", t + 2,
                              T["std_msgs/msg/String"](data=text))
            if answer is not None:
                bag.write_message("/goal_pose", "geometry_msgs/msg/PoseStamped", t + 3,
                                  pose_at(answer))
                if with_values:
                    r2, t2 = world.reward_map(np.zeros((10, 10), bool), answer)
                    bag.write_message("/value_map_raw", "std_msgs/msg/Float32MultiArray", t + 4,
                                      multiarray(world.value_iteration(r2, t2)))
    return path


def test_md_from_a_standard_types_bag(tmp_path, capsys):
    bag = write_bag(tmp_path / "bag", [("a", (1, 1), (1, 1)), ("b", (2, 3), (4, 4)),
                                       ("c", None, (0, 0)), ("d", (9, 0), (0, 0))])
    m = evaluate_bag(bag).metrics()
    assert m["n"] == 3 and m["unanswered"] == 1
    assert m["md"] == pytest.approx((0 + 3 + 9) / 3)
    assert "pq" not in m
    assert cli.main(["eval-bag", str(bag), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["n"] == 3 and out["md"] == pytest.approx(4.0)


def test_pq_and_mse_when_value_maps_are_recorded(tmp_path):
    bag = write_bag(tmp_path / "bag", [("a", (1, 1), (1, 1)), ("b", (5, 5), (5, 6))],
                    with_values=True)
    m = evaluate_bag(bag).metrics()
    assert m["n"] == 2 and m["n_value_maps"] == 2
    assert m["md"] == pytest.approx(0.5)
    assert 0.0 < m["pq"] < 1.0 and m["mse"] > 0  # the second answer is one cell off
    perfect = evaluate_bag(write_bag(tmp_path / "bag2", [("a", (2, 2), (2, 2))],
                                     with_values=True)).metrics()
    assert perfect["pq"] == pytest.approx(1.0) and perfect["mse"] == pytest.approx(0.0)


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    assert cli.main(["eval-bag", str(tmp_path / "missing")]) == 2
    assert "not found" in capsys.readouterr().err
    junk = tmp_path / "junk.txt"
    junk.write_text("not a bag")
    assert cli.main(["eval-bag", str(junk)]) == 2
    assert "not a rosbag2 bag" in capsys.readouterr().err
    no_map = write_bag(tmp_path / "nomap", [("a", (1, 1), (1, 1))], skip=("map",))
    assert cli.main(["eval-bag", str(no_map)]) == 2
    err = capsys.readouterr().err
    assert "entity_map" in err and err.count("\n") == 1
    truncated = write_bag(tmp_path / "trunc", [("a", (1, 1), (1, 1))] * 50)
    mcap = next(truncated.glob("*.mcap"))
    mcap.write_bytes(mcap.read_bytes()[: mcap.stat().st_size // 2])
    assert cli.main(["eval-bag", str(truncated)]) == 2
    assert "spatial-grounding: error:" in capsys.readouterr().err
