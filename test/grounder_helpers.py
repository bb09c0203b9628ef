# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Shared by the grounder node tests.

Small checkpoints that need no training, and a probe node that talks to the grounder over DDS and
keeps everything it hears.
"""

from __future__ import annotations

import itertools
import os
from pathlib import Path
import secrets
import signal
import subprocess

import numpy as np
from spatial_grounding_ros.core.entities import PUDDLEWORLD
from spatial_grounding_ros.core.text import Vocabulary
from spatial_grounding_ros.data.generator import generate
from spatial_grounding_ros.models.checkpoints import save_checkpoint
from spatial_grounding_ros.models.config import ModelConfig
from spatial_grounding_ros.models.registry import build_model
import torch

MODEL = 't-rnet-attn'
# the grounder's default table is the office one (the entity mapper's); PuddleWorld maps need
# this (issue 42)
PUDDLEWORLD_YAML = 'entities_puddleworld.yaml'
try:
    from rclpy.parameter import Parameter

    PUDDLEWORLD_TABLE = Parameter('entity_table', value=PUDDLEWORLD_YAML)
    # the small untrained checkpoints here are never calibrated: their confidence means little,
    # and the default min_confidence (0.1) would decline their every goal
    ANY_CONFIDENCE = Parameter('min_confidence', value=0.0)
except ImportError:  # the tests that need it skip without rclpy
    PUDDLEWORLD_TABLE = ANY_CONFIDENCE = None


def unique_namespace(base: str) -> str:
    """
    `/<base>_<pid>_<random>`: a namespace of this run's own.

    The ROS_DOMAIN_ID of a run is one of 100, so two runs on one host can share a domain; in their
    own namespaces they cannot hear each other's maps, instructions or goals (or diagnostics, which
    the probe filters by the node's full name).
    """
    return f'/{base}_{os.getpid()}_{secrets.token_hex(3)}'


def generator_vocabulary() -> Vocabulary:
    return Vocabulary.build(generate(300, seed=1, mode='mixed').instructions)


def random_checkpoint(path: Path) -> Path:
    """
    Seeded, untrained t-RNetAttn.

    Its answer depends on the whole grid and text, so a node that flipped or mangled its input
    would disagree with the Python API.
    """
    vocab = generator_vocabulary()
    cfg = ModelConfig(n_entities=len(PUDDLEWORLD), vocab_size=len(vocab))
    torch.manual_seed(0)
    return save_checkpoint(
        path, MODEL, build_model(MODEL, cfg), cfg, vocab, PUDDLEWORLD, task='test: random weights'
    )


def north_east_checkpoint(path: Path) -> Path:
    """
    t-RNetAttn with hand-set weights whose value map is 0.1*G1 - G2.

    Largest in data-set row 0 (north, G2 = -1) and then in the last column (east, G1 = +1),
    whatever the map or instruction. The model's own notion of north, with no training involved.
    """
    vocab = generator_vocabulary()
    cfg = ModelConfig(n_entities=len(PUDDLEWORLD), vocab_size=len(vocab), head=())
    model = build_model(MODEL, cfg)
    with torch.no_grad():
        for p in model.parameters():
            p.zero_()
        model.decoder.bias[-3:] = torch.tensor([0.1, -1.0, 0.0])  # Z2 = b1*G1 + b2*G2 + b3*J
        model.head.convs[0].weight[0, 1, 1, 1] = 1.0  # value = Z2 (centre tap)
    return save_checkpoint(
        path, MODEL, model, cfg, vocab, PUDDLEWORLD, task='test: hand-set north-east model'
    )


def make_probe(context, namespace: str, grounder_name: str):
    """
    Return a node that publishes maps and instructions and records the grounder's outputs.

    A node that publishes entity maps and instructions into `namespace` and records the
    grounder's outputs, its diagnostics and its /rosout lines.
    """
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import OccupancyGrid
    from rcl_interfaces.msg import Log
    from rclpy.node import Node
    from sensor_msgs.msg import Image
    from spatial_grounding_ros.ros import convert
    from spatial_grounding_ros.ros.qos import LATCHED
    from std_msgs.msg import Float32MultiArray, Header, String

    logger_name = grounder_name.strip('/').replace('/', '.')  # how /rosout names its lines

    class GrounderProbe(Node):
        RECORDS = (
            'goals',
            'value_maps',
            'raw_maps',
            'images',
            'relation_maps',
            'diagnostics',
            'statuses',
            'warnings',
        )

        def __init__(self):
            super().__init__('grounder_probe', namespace=namespace, context=context)
            self.goals, self.value_maps, self.raw_maps, self.relation_maps = [], [], [], []
            self.diagnostics, self.warnings = [], []
            self.images, self.statuses = [], []  # value_map_image; the 1 Hz `<node>: status`
            self.stamps = itertools.count(1)
            sub = self.create_subscription
            self.goal_sub = sub(PoseStamped, 'goal_pose', self.goals.append, 10)
            sub(OccupancyGrid, 'value_map', self.value_maps.append, LATCHED)
            sub(Float32MultiArray, 'value_map_raw', self.raw_maps.append, LATCHED)
            sub(OccupancyGrid, 'relation_map', self.relation_maps.append, LATCHED)
            sub(Image, 'value_map_image', self.images.append, LATCHED)
            self.diagnostics_sub = sub(DiagnosticArray, '/diagnostics', self.on_diagnostics, 100)
            sub(Log, '/rosout', self.on_log, 100)
            self.map_pub = self.create_publisher(OccupancyGrid, 'entity_map', LATCHED)
            self.instruction_pub = self.create_publisher(String, 'instruction', 10)
            self.robot_pose_pub = self.create_publisher(PoseStamped, 'robot_pose', 10)

        def counts(self) -> dict:
            """How many of each output so far; pass to new() to get what came after."""
            return {k: len(v) for k, v in self.__dict__.items() if k in self.RECORDS}

        def new(self, record: str, counts: dict) -> list:
            return getattr(self, record)[counts[record]:]

        def on_diagnostics(self, msg):
            # the periodic status apart: the events' tests count diagnostics one per event
            for status in msg.status:
                if status.name == f'{grounder_name}: status':
                    self.statuses.append(status)
                elif status.name.startswith(grounder_name + ':'):
                    self.diagnostics.append(status)

        def on_log(self, msg):
            # /rosout is global: keep the lines of this namespace's grounder only
            if msg.name == logger_name and msg.level >= Log.WARN:
                self.warnings.append(msg.msg)

        def holds(self, message) -> bool:
            """
            Tell whether the grounder said that it holds the map `message`.

            Whether the grounder said (its OK `entity_map` diagnostic) that it holds the map
            `message`, told apart from earlier maps by its stamp.
            """
            stamp = {
                'stamp_sec': str(message.header.stamp.sec),
                'stamp_nanosec': str(message.header.stamp.nanosec),
            }
            return any(
                s.name == f'{grounder_name}: entity_map'
                and s.level == DiagnosticStatus.OK
                and stamp.items() <= {v.key: v.value for v in s.values}.items()
                for s in self.diagnostics
            )

        def connected(self) -> bool:
            # matched, not just seen in the graph: a message (an instruction, a robot pose, a
            # diagnostic) sent before the match is lost; wait for this before the first publish
            diagnostics = self.get_publishers_info_by_topic('/diagnostics')
            return (
                self.instruction_pub.get_subscription_count() > 0
                and self.map_pub.get_subscription_count() > 0
                and self.robot_pose_pub.get_subscription_count() > 0
                and self.goal_sub.get_publisher_count() > 0
                and any(
                    f"{p.node_namespace.rstrip('/')}/{p.node_name}" == grounder_name
                    for p in diagnostics
                )
                and self.diagnostics_sub.get_publisher_count() >= len(diagnostics)
            )

        def publish_map(self, grid=None, info=None, frame_id='map', message=None):
            """
            Publish an entity map (a data-set grid, or a ready message); returns it.

            Each map gets a distinct stamp so a test can tell which one the grounder holds.
            """
            if message is None:
                header = Header(frame_id=frame_id)
                message = convert.grid_to_occupancy_grid(np.asarray(grid), header, info)
            message.header.stamp.sec = next(self.stamps)
            self.map_pub.publish(message)
            return message

        def publish_instruction(self, text: str) -> None:
            self.instruction_pub.publish(String(data=text))

    return GrounderProbe()


def interrupt(process) -> tuple[int, str]:
    """Stop a node process as Ctrl-C would (killing it if it hangs); its exit code and output."""
    process.send_signal(signal.SIGINT)
    try:
        output, _ = process.communicate(timeout=15)
    except subprocess.TimeoutExpired:
        # the node's faulthandler then prints where each of its threads hangs
        process.send_signal(signal.SIGABRT)
        try:
            output, _ = process.communicate(timeout=5)
        except subprocess.TimeoutExpired:
            process.kill()
            output, _ = process.communicate()
    return process.returncode, output
