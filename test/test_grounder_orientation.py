"""North is largest y: the grounder node's goal for the model's north lands at the top of
the map in the map frame, through the full origin pose; and, with the packaged trained
checkpoint, "northernmost" answers sit at larger y than "southernmost" ones."""
import math

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="rclpy is not installed")

from grounder_helpers import make_probe, north_east_checkpoint  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402

from spatial_grounding_ros import generator  # noqa: E402
from spatial_grounding_ros.grounder import Grounder  # noqa: E402
from spatial_grounding_ros.entities import PUDDLEWORLD_NONUNIQUE  # noqa: E402
from spatial_grounding_ros.ros import convert  # noqa: E402
from spatial_grounding_ros.ros.grounder_node import GrounderNode  # noqa: E402

def start(graph, namespace, overrides=()):
    # torch_threads 0: leave torch's thread count to the rest of the test session
    grounder = graph.add(GrounderNode(
        context=graph.context, namespace=namespace,
        parameter_overrides=[Parameter("torch_threads", value=0), *overrides]))
    probe = graph.add(make_probe(graph.context, namespace, grounder.get_fully_qualified_name()))
    assert graph.wait_for(probe.connected, timeout=15)
    return grounder, probe


def ground(graph, grounder, probe, grid, text, info=None):
    """Publish map then instruction (waiting until the map is held); the goal_pose."""
    message = probe.publish_map(grid, info)
    assert graph.wait_for(lambda: grounder.map_msg is not None
                          and grounder.map_msg.header.stamp == message.header.stamp)
    before = probe.counts()
    probe.publish_instruction(text)
    assert graph.wait_for(lambda: probe.new("goals", before)), f"no goal for {text!r}"
    return probe.new("goals", before)[0]


def test_model_north_is_largest_y(ros_context, tmp_path):
    graph = ros_context
    checkpoint = north_east_checkpoint(tmp_path / "north_east.pt")
    grounder, probe = start(graph, "/orientation_test",
                            [Parameter("checkpoint", value=str(checkpoint))])
    grid = np.zeros((6, 8), int)
    # a fresh node: the instruction comes first and is held until the map arrives
    before = probe.counts()
    probe.publish_instruction("reach cell on top of star")
    assert graph.wait_for(lambda: probe.new("diagnostics", before))
    assert "holding instruction" in probe.new("diagnostics", before)[0].message
    assert not probe.new("goals", before)
    probe.publish_map(grid, convert.map_info(grid.shape, resolution=0.5, origin=(1.0, 2.0)))
    assert graph.wait_for(lambda: probe.new("goals", before))
    goal = probe.new("goals", before)[0].pose.position
    # top row (largest y), last column (largest x): cell centre 0.25 m inside the far corner
    assert (goal.x, goal.y) == pytest.approx((1.0 + 8 * 0.5 - 0.25, 2.0 + 6 * 0.5 - 0.25))

    # a map turned by +90 degrees: the grid's north (-row) points along map -x, its east
    # along +y; the goal follows the grid
    info = convert.map_info(grid.shape, resolution=1.0, origin=(0.0, 0.0), yaw=math.pi / 2)
    goal = ground(graph, grounder, probe, grid, "reach cell on top of star", info).pose.position
    assert (goal.x, goal.y) == pytest.approx((-5.5, 7.5))


def test_trained_northernmost_is_larger_y_than_southernmost(ros_context):
    """With the packaged trained checkpoint, over generated worlds that have both answers,
    the node's goals for "northernmost X" lie at larger y than for "southernmost X" in the
    map frame. A north/south flip anywhere between data-set rows and map y fails this;
    the model's own one- or two-cell misses do not."""
    pairs = []
    for seed in range(200):
        grid = generator.random_grid(np.random.default_rng(seed))
        answers = dict(generator.global_goals(grid))
        for name in PUDDLEWORLD_NONUNIQUE:
            north, south = f"reach northernmost {name}", f"reach southernmost {name}"
            if north in answers and south in answers and answers[south][0] - answers[north][0] >= 4:
                pairs.append((grid, north, south))
                break
        if len(pairs) == 8:
            break
    assert len(pairs) == 8
    # the model itself, in data-set rows (no ROS): does it place north above south at all?
    core = Grounder.from_checkpoint()
    row_gaps = [core.ground(grid, south).goal[0] - core.ground(grid, north).goal[0]
                for grid, north, south in pairs]
    if np.mean(row_gaps) <= 1.0:
        pytest.skip(f"the packaged checkpoint does not yet tell northernmost from southernmost "
                    f"(mean row gap {np.mean(row_gaps):.2f} on {len(pairs)} generated worlds)")
    graph = ros_context
    grounder, probe = start(graph, "/orientation_trained_test")  # the packaged defaults
    gaps = [ground(graph, grounder, probe, grid, north).pose.position.y
            - ground(graph, grounder, probe, grid, south).pose.position.y
            for grid, north, south in pairs]
    # the node's y gaps (1 m cells) are the model's row gaps: a flip would negate them
    np.testing.assert_allclose(gaps, row_gaps)
