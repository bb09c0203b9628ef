"""The bag recorder over real DDS: latched topics are subscribed transient local (a map
latched before recording started is in the bag) and marked transient local in the bag's
metadata, so `ros2 bag play` offers them latched again; other topics are volatile; the bytes
stored are the CDR the publisher sent."""
import numpy as np
import pytest
import yaml

pytest.importorskip("rclpy", reason="rclpy is not installed")

from grounder_helpers import unique_namespace  # noqa: E402
from nav_msgs.msg import OccupancyGrid  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.serialization import serialize_message  # noqa: E402
from std_msgs.msg import Header, String  # noqa: E402

from spatial_grounding_ros.bags import open_bag  # noqa: E402
from spatial_grounding_ros.ros import convert  # noqa: E402
from spatial_grounding_ros.ros.bag_recorder import LATCHED_QOS, BagRecorder  # noqa: E402


def test_latched_topics_are_recorded_and_marked_transient_local(ros_context, tmp_path):
    graph = ros_context
    namespace = unique_namespace("recorder_test")
    source = graph.add(Node("source", namespace=namespace, context=graph.context))
    map_pub = source.create_publisher(OccupancyGrid, "entity_map", LATCHED_QOS)
    text_pub = source.create_publisher(String, "instruction", 10)
    grid = convert.grid_to_occupancy_grid(np.arange(12).reshape(3, 4), Header(frame_id="map"))
    map_pub.publish(grid)  # latched before the recorder exists
    recorder = graph.add(BagRecorder(tmp_path / "bag", {
        "entity_map": "nav_msgs/msg/OccupancyGrid", "instruction": "std_msgs/msg/String"},
        latched={"entity_map"}, namespace=namespace, context=graph.context))
    assert graph.wait_for(lambda: recorder.counts.get(f"{namespace}/entity_map") == 1)
    assert graph.wait_for(lambda: text_pub.get_subscription_count() > 0)
    text_pub.publish(String(data="reach cell on top of star"))
    assert graph.wait_for(lambda: recorder.counts.get(f"{namespace}/instruction") == 1)
    graph.executor.remove_node(recorder)  # nothing arrives while the bag closes
    recorder.close()

    info = yaml.safe_load((tmp_path / "bag" / "metadata.yaml").read_text())
    info = info["rosbag2_bagfile_information"]
    assert info["version"] == 9 and info["storage_identifier"] == "mcap"
    qos = {t["topic_metadata"]["name"]: t["topic_metadata"]["offered_qos_profiles"]
           for t in info["topics_with_message_count"]}
    [latched] = qos[f"{namespace}/entity_map"]
    [stream] = qos[f"{namespace}/instruction"]
    assert (latched["durability"], latched["reliability"], latched["depth"]) == (
        "transient_local", "reliable", 1)
    assert (stream["durability"], stream["reliability"]) == ("volatile", "reliable")

    reader = open_bag(tmp_path / "bag")
    try:
        stored = {c.topic: raw for c, _, raw in reader.messages()}
    finally:
        reader.close()
    assert stored[f"{namespace}/entity_map"] == serialize_message(grid)
    assert stored[f"{namespace}/instruction"] == serialize_message(
        String(data="reach cell on top of star"))
