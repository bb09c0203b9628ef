# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The bag recorder over real DDS writes what `ros2 bag record -s mcap` of Jazzy writes.

- Latched topics are subscribed transient local (a map latched before recording started is
  in the bag); the bytes stored are the CDR the publisher sent.
- Each topic's offered_qos_profiles are the publishers' QoS as the graph reports them, not
  the recorder's own subscription QoS; each channel has its topic_type_hash (RIHS01), the
  metadata says ros_distro: jazzy (read back with the independent `mcap` reader too).
- log_time is the reception time, even when the recorder's thread is busy when the message
  arrives, and publish_time the publisher's send time.

No assertion here bounds an elapsed time: the times in the bag are checked by their order
against events the test saw (before a publish, after the recorder counted the message, before
the busy thread was let go), which holds however slow the machine is.
"""

import threading
import time

import numpy as np
import pytest
import yaml

pytest.importorskip('rclpy', reason='rclpy is not installed')
make_reader = pytest.importorskip(
    'mcap.reader', reason='the mcap reader is not installed (pip install mcap, requirements.txt)'
).make_reader

from grounder_helpers import unique_namespace  # noqa: E402, I100
from nav_msgs.msg import OccupancyGrid  # noqa: E402
from rclpy.duration import Duration  # noqa: E402
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402
from rclpy.serialization import deserialize_message  # noqa: E402
from spatial_grounding_ros.data.bags import open_bag, typestore  # noqa: E402
from spatial_grounding_ros.ros import convert  # noqa: E402
from spatial_grounding_ros.ros.bag_recorder import BagRecorder  # noqa: E402
from spatial_grounding_ros.ros.qos import LATCHED  # noqa: E402
from std_msgs.msg import Header, String  # noqa: E402

INFINITE = {'sec': 9223372036, 'nsec': 854775807}  # RMW_DURATION_INFINITE


def spin_quietly(executor) -> None:
    try:
        executor.spin()
    except ExternalShutdownException:
        pass


def topic_metadata(bag) -> dict:
    info = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    return info, {
        t['topic_metadata']['name']: t['topic_metadata'] for t in info['topics_with_message_count']
    }


def test_recorded_qos_type_hashes_and_distro_are_what_ros2_bag_record_writes(
    ros_context, tmp_path
):
    graph = ros_context
    namespace = unique_namespace('recorder_test')
    source = graph.add(Node('source', namespace=namespace, context=graph.context))
    map_pub = source.create_publisher(OccupancyGrid, 'entity_map', LATCHED)
    # latched like the gridworld's instruction, with a deadline: the recorder subscribes
    # volatile, so only the publisher's own QoS can put transient_local and 5 s in the bag
    text_qos = QoSProfile(
        depth=1,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL,
        deadline=Duration(seconds=5),
    )
    text_pub = source.create_publisher(String, 'instruction', text_qos)
    second_text_pub = source.create_publisher(String, 'instruction', 10)  # a 2nd publisher
    grid = convert.grid_to_occupancy_grid(np.arange(12).reshape(3, 4), Header(frame_id='map'))
    map_pub.publish(grid)  # latched before the recorder exists
    recorder = graph.add(
        BagRecorder(
            tmp_path / 'bag',
            {'entity_map': 'nav_msgs/msg/OccupancyGrid', 'instruction': 'std_msgs/msg/String'},
            latched={'entity_map'},
            namespace=namespace,
            context=graph.context,
        )
    )
    assert graph.wait_for(lambda: recorder.counts.get(f'{namespace}/entity_map') == 1)
    assert graph.wait_for(
        lambda: (
            text_pub.get_subscription_count() > 0 and second_text_pub.get_subscription_count() > 0
        ),
    )
    before_publish = time.time_ns()
    text_pub.publish(String(data='reach cell on top of star'))
    assert graph.wait_for(lambda: recorder.counts.get(f'{namespace}/instruction') == 1)
    after_recorded = time.time_ns()
    graph.executor.remove_node(recorder)  # nothing arrives while the bag closes
    recorder.close()

    info, topics = topic_metadata(tmp_path / 'bag')
    assert info['version'] == 9 and info['storage_identifier'] == 'mcap'
    assert info['ros_distro'] == 'jazzy'
    [latched] = topics[f'{namespace}/entity_map']['offered_qos_profiles']
    # history and depth are not discovered: ros2 bag record stores 'unknown' and 0 too
    assert latched == {
        'history': 'unknown',
        'depth': 0,
        'reliability': 'reliable',
        'durability': 'transient_local',
        'deadline': INFINITE,
        'lifespan': INFINITE,
        'liveliness': 'automatic',
        'liveliness_lease_duration': INFINITE,
        'avoid_ros_namespace_conventions': False,
    }
    offered = topics[f'{namespace}/instruction']['offered_qos_profiles']
    assert sorted((q['durability'], q['deadline']['sec']) for q in offered) == [
        ('transient_local', 5),
        ('volatile', INFINITE['sec']),
    ]
    store = typestore()
    for name, msgtype in (
        (f'{namespace}/entity_map', 'nav_msgs/msg/OccupancyGrid'),
        (f'{namespace}/instruction', 'std_msgs/msg/String'),
    ):
        advertised = str(source.get_publishers_info_by_topic(name)[0].topic_type_hash)
        assert advertised.startswith('RIHS01_') and len(advertised) == 7 + 64
        assert topics[name]['type_description_hash'] == advertised
        assert advertised == store.hash_rihs01(msgtype)  # the definitions stored are Jazzy's

    # the MCAP file, read with the independent `mcap` library
    [mcap_file] = (tmp_path / 'bag').glob('*.mcap')
    with open(mcap_file, 'rb') as stream:
        reader = make_reader(stream)
        assert reader.get_header().profile == 'ros2'
        channels = {c.topic: c for c in reader.get_summary().channels.values()}
        messages = {
            c.topic: (m.log_time, m.publish_time, m.data) for _, c, m in reader.iter_messages()
        }
        [metadata] = [m for m in reader.iter_metadata() if m.name == 'rosbag2']
    for name, meta in topics.items():
        assert channels[name].metadata['topic_type_hash'] == meta['type_description_hash']
        assert (
            yaml.safe_load(channels[name].metadata['offered_qos_profiles'])
            == meta['offered_qos_profiles']
        )
    assert yaml.safe_load(metadata.metadata['serialized_metadata'])['ros_distro'] == 'jazzy'
    # the messages as sent; compared as messages, since the bytes' alignment padding (after
    # the map's height, before its origin's float64s) is whatever the sender's buffer held
    recorded_map = deserialize_message(messages[f'{namespace}/entity_map'][2], OccupancyGrid)
    assert recorded_map == grid
    log_time, publish_time, data = messages[f'{namespace}/instruction']
    assert deserialize_message(data, String) == String(data='reach cell on top of star')
    # sent, received and recorded in this order, all within the test's own window
    assert before_publish <= publish_time <= log_time <= after_recorded

    reader = open_bag(tmp_path / 'bag')  # and rosbags reads it back as before
    try:
        assert len(list(reader.messages())) == 2
    finally:
        reader.close()


def test_log_time_is_reception_not_when_a_busy_thread_gets_to_the_callback(ros_context, tmp_path):
    """
    Check that a message's log time is its reception, not when a busy thread gets to it.

    The recorder's executor thread is held (as the demo's thread was while drawing a PNG)
    until a witness in another thread has received the message; only then is it let go. The
    bag's log_time must come before that release (so it is not when the callback ran) and
    after the publish. Ordering only: no bound on how long anything takes.
    """
    graph = ros_context
    namespace = unique_namespace('recorder_busy_test')
    source = graph.add(Node('source', namespace=namespace, context=graph.context))
    pub = source.create_publisher(String, 'agent_pose_like', 10)
    recorder = graph.add(
        BagRecorder(
            tmp_path / 'bag',
            {'agent_pose_like': 'std_msgs/msg/String'},
            namespace=namespace,
            context=graph.context,
        )
    )
    # the witness spins in an executor of its own, so it hears the message while the
    # recorder's executor thread is held
    witness_heard = threading.Event()
    witness = Node('witness', namespace=namespace, context=graph.context)
    witness.create_subscription(String, 'agent_pose_like', lambda msg: witness_heard.set(), 10)
    witness_executor = SingleThreadedExecutor(context=graph.context)
    witness_executor.add_node(witness)
    witness_thread = threading.Thread(target=spin_quietly, args=(witness_executor,), daemon=True)
    witness_thread.start()
    held, release = threading.Event(), threading.Event()

    def hold_once():
        timer.cancel()
        held.set()
        release.wait(timeout=120)  # the executor thread (the recorder's too) does nothing else

    timer = source.create_timer(0.01, hold_once)
    try:
        assert graph.wait_for(lambda: pub.get_subscription_count() >= 2)
        assert held.wait(timeout=60), 'the executor thread was never held'
        sent = time.time_ns()
        pub.publish(String(data='moved'))
        assert witness_heard.wait(timeout=60), 'the witness never heard the message'
        assert not recorder.counts, 'the held thread recorded the message'
        released = time.time_ns()
    finally:
        release.set()
    assert graph.wait_for(lambda: recorder.counts.get(f'{namespace}/agent_pose_like') == 1)
    graph.executor.remove_node(recorder)
    recorder.close()
    witness_executor.shutdown()
    witness_thread.join(timeout=10)
    witness.destroy_node()
    [mcap_file] = (tmp_path / 'bag').glob('*.mcap')
    with open(mcap_file, 'rb') as stream:
        [(_, _, message)] = list(make_reader(stream).iter_messages())
    # received while the thread was held: the callback itself only ran after `released`
    assert sent <= message.log_time < released, (sent, message.log_time, released)
    assert sent <= message.publish_time <= message.log_time
