# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
rosbag2 (MCAP) bags without rclpy, with the `rosbags` library.

A writer for the recorder, and `spatial-grounding eval-bag`, which scores the goals recorded in a
bag.

Bags are written as `ros2 bag record -s mcap` of Jazzy writes them: rosbag2 metadata version
9, `ros_distro: jazzy`, MCAP storage with the Jazzy type store's message definitions, each
channel's `offered_qos_profiles` (the publishers' QoS, when the recorder knows them) and
`topic_type_hash` (RIHS01), and each message's log_time (reception) and publish_time.

Evaluation pairs every instruction with the goal_pose that answered it (the first goal after
the instruction and before the next one) and with the truth recorded for it (the latest
true_goal after the previous answer and up to this answer: the gridworld node publishes the
truth just before the instruction, other tools may publish it after). Cells come from the
entity_map's geometry (resolution, origin) as of the answer. MD is the mean Manhattan
distance in cells; with value_map_raw, true_value_map and true_reward_map recorded too, PQ and
MSE are computed as world.evaluate_maps does (the goal cell is the terminal one).
"""

from __future__ import annotations

from dataclasses import dataclass, field
import json
from pathlib import Path

import numpy as np

from ..core import topics, world
from ..core.map_geometry import multiarray_to_map, point_to_cell

STORE = 'ROS2_JAZZY'
ROS_DISTRO = 'jazzy'
BAG_VERSION = 9
TOPICS = {  # role -> default topic name (relative names match any namespace)
    'instruction': topics.INSTRUCTION,
    'goal': topics.GOAL_POSE,
    'truth': topics.TRUE_GOAL,
    'map': topics.ENTITY_MAP,
    'values': topics.VALUE_MAP_RAW,
    'true_values': topics.TRUE_VALUE_MAP,
    'true_rewards': topics.TRUE_REWARD_MAP,
}
MSGTYPES = {role: topics.MSGTYPES[topic] for role, topic in TOPICS.items()}
REQUIRED = ('instruction', 'goal', 'truth', 'map')


def typestore():
    from rosbags.typesys import get_typestore, Stores

    return get_typestore(getattr(Stores, STORE))


INFINITE_NS = 2**63 - 1  # RMW_DURATION_INFINITE, as rclpy reports it


def duration(ns: int):
    """Return a rosbags QosTime of `ns` nanoseconds (infinite = 9223372036 s 854775807 ns)."""
    from rosbags.interfaces import QosTime

    sec, nsec = divmod(int(ns), 10**9)
    return QosTime(sec=sec, nsec=nsec)


def qos(latched: bool, depth: int = 1000):
    """
    Return a stand-in QoS profile for a topic whose publishers are unknown.

    A stand-in QoS profile for a topic whose publishers are unknown (a bag written from
    messages, not recorded): transient local for latched topics, so `ros2 bag play` offers
    them latched again.
    """
    from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability

    infinite = duration(INFINITE_NS)
    return Qos(
        history=QosHistory.KEEP_LAST,
        depth=1 if latched else depth,
        reliability=QosReliability.RELIABLE,
        durability=QosDurability.TRANSIENT_LOCAL if latched else QosDurability.VOLATILE,
        deadline=infinite,
        lifespan=infinite,
        liveliness=QosLiveliness.AUTOMATIC,
        liveliness_lease_duration=infinite,
        avoid_ros_namespace_conventions=False,
    )


def _jazzy_writer_classes():
    """
    Build rosbags' rosbag2 Writer and MCAP storage, completed as Jazzy's MCAP plugin writes.

    rosbags' rosbag2 Writer and its MCAP storage, with what rosbags 0.11 leaves out and
    rosbag2's Jazzy MCAP plugin writes: each channel's `topic_type_hash` beside
    `offered_qos_profiles`, a message's publish_time apart from its log_time, and
    `ros_distro: jazzy` (rosbags writes `rosbags`) in the bag's metadata, both the embedded
    copy and metadata.yaml.
    """
    from io import BytesIO

    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.rosbag2.storage_mcap import (
        Channel,
        McapWriter,
        write_channel,
        write_record,
        write_string,
        write_uint16,
        write_uint32,
        write_uint64,
    )
    import yaml

    class JazzyMcapWriter(McapWriter):
        publish_time: int | None = None  # of the next message; None: its log_time

        def add_connection(self, connection, offered_qos_profiles: str) -> None:
            metadata = BytesIO()
            for key, value in (
                ('offered_qos_profiles', offered_qos_profiles),
                ('topic_type_hash', connection.digest),
            ):
                write_string(metadata, key)
                write_string(metadata, value)
            self.channels.append(
                Channel(
                    connection.id,
                    connection.msgtype,
                    connection.topic,
                    connection.ext.serialization_format,
                    metadata.getvalue(),
                )
            )
            self.channel_stats[connection.id] = 0
            write_channel(self.chunk.bio, self.channels[-1], self.schemas)

        def write(self, connection, timestamp: int, data) -> None:
            publish_time = timestamp if self.publish_time is None else self.publish_time
            self.message_start_time = min(timestamp, self.message_start_time)
            self.message_end_time = max(timestamp, self.message_end_time)
            self.channel_stats[connection.id] += 1
            self.chunk.message_start_time = min(timestamp, self.chunk.message_start_time)
            self.chunk.message_end_time = max(timestamp, self.chunk.message_end_time)
            self.chunk.msgs[connection.id].append((timestamp, self.chunk.bio.tell()))
            record = BytesIO()
            write_uint16(record, connection.id)
            write_uint32(record, 0)  # sequence
            write_uint64(record, timestamp)  # log_time: when the recorder received it
            write_uint64(record, publish_time)  # publish_time: when it was sent
            record.write(data)
            write_record(self.chunk.bio, 0x05, record)
            if self.chunk.bio.tell() > 2**20:
                self.close_chunk()

        def close(self, version: int, metadata: str) -> None:
            info = yaml.safe_load(metadata)
            info['ros_distro'] = ROS_DISTRO
            super().close(version, yaml.safe_dump(info, sort_keys=False).strip())

    class JazzyWriter(Writer):
        STORAGE_PLUGINS = {**Writer.STORAGE_PLUGINS, StoragePlugin.MCAP: JazzyMcapWriter}

        def close(self) -> None:
            super().close()
            info = yaml.safe_load(self.metapath.read_text())
            info['rosbag2_bagfile_information']['ros_distro'] = ROS_DISTRO
            self.metapath.write_text(yaml.safe_dump(info, sort_keys=False))

    return JazzyWriter, StoragePlugin.MCAP


class BagWriter:
    """
    Serialized (CDR) messages into a new rosbag2 MCAP bag directory.

        with BagWriter("run1") as bag:
            bag.write("/gridworld/instruction", "std_msgs/msg/String", t_ns, cdr_bytes)

    A topic's connection is made at its first message, with the `offered_qos` and
    `type_hash` given then (a recorder passes the publishers'), else a stand-in QoS (see
    qos()) and the type store's hash.
    """

    def __init__(self, path: str | Path, latched: set[str] = frozenset()):
        self.path = Path(path)
        if self.path.exists():
            raise FileExistsError(f'{self.path}: already exists; a bag needs a new directory')
        self.store, self.latched = typestore(), set(latched)
        writer_class, storage = _jazzy_writer_classes()
        self.writer = writer_class(self.path, version=BAG_VERSION, storage_plugin=storage)
        self.connections = {}
        self.counts: dict[str, int] = {}

    def __enter__(self) -> 'BagWriter':
        self.writer.open()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        if self.writer is not None:
            self.writer.close()
            self.writer = None

    def write(
        self,
        topic: str,
        msgtype: str,
        timestamp_ns: int,
        data: bytes,
        *,
        publish_time_ns: int | None = None,
        offered_qos: list | None = None,
        type_hash: str | None = None,
    ) -> None:
        """
        Store one message.

        `timestamp_ns` is its log_time (reception), `publish_time_ns` when it was sent (default:
        the same).
        """
        if topic not in self.connections:
            msgdef, _ = self.store.generate_msgdef(msgtype, ros_version=2)
            self.connections[topic] = self.writer.add_connection(
                topic,
                msgtype,
                msgdef=msgdef,
                rihs01=type_hash or self.store.hash_rihs01(msgtype),
                offered_qos_profiles=offered_qos or [qos(topic in self.latched)],
            )
            self.counts[topic] = 0
        storage = self.writer.storage
        storage.publish_time = None if publish_time_ns is None else int(publish_time_ns)
        try:
            self.writer.write(self.connections[topic], int(timestamp_ns), bytes(data))
        finally:
            storage.publish_time = None
        self.counts[topic] += 1

    def write_message(self, topic: str, msgtype: str, timestamp_ns: int, msg) -> None:
        """Serialize a rosbags message object (from `typestore().types[msgtype]`) and write it."""
        self.write(topic, msgtype, timestamp_ns, self.store.serialize_cdr(msg, msgtype))


def open_bag(path: str | Path):
    """
    Return a rosbags Reader over a bag directory (or its .mcap/.db3 file), opened.

    Clear errors for a missing path or something that is not a readable rosbag2 bag.
    """
    from rosbags.rosbag2 import Reader

    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f'{path}: bag not found')
    if path.is_file():
        if not (path.parent / 'metadata.yaml').is_file():
            raise ValueError(
                f'{path}: not a rosbag2 bag (a bag is a directory with '
                'metadata.yaml and .mcap or .db3 files)'
            )
        path = path.parent
    if not (path / 'metadata.yaml').is_file():
        raise ValueError(f'{path}: not a rosbag2 bag (no metadata.yaml)')
    try:
        reader = Reader(path)
        reader.open()
    except Exception as exc:  # rosbags raises its own error types and OSError/KeyError on junk
        raise ValueError(
            f'{path}: not a readable rosbag2 bag ({type(exc).__name__}: {exc})'
        ) from exc
    return reader


def resolve_topics(available: dict[str, str], wanted: dict[str, str]) -> dict[str, str]:
    """
    Map each role to its topic in the bag.

    An absolute name must match exactly; a relative one matches a topic ending in /name (any
    namespace). Ambiguity is an error naming the candidates.
    """
    found = {}
    for role, name in wanted.items():
        if name.startswith('/'):
            matches = [t for t in available if t == name]
        else:
            matches = [t for t in available if t == '/' + name or t.endswith('/' + name)]
        if len(matches) > 1:
            raise ValueError(
                f'several topics match {name!r} ({", ".join(sorted(matches))}): '
                f'pass the full name with --{role.replace("_", "-")}-topic'
            )
        if matches:
            topic = matches[0]
            if available[topic] != MSGTYPES[role]:
                raise ValueError(
                    f'topic {topic} has type {available[topic]}, expected '
                    f'{MSGTYPES[role]} for the {role} topic'
                )
            found[role] = topic
    return found


@dataclass
class Episode:
    instruction: str
    goal: tuple[int, int]
    truth: tuple[int, int]
    values: np.ndarray | None = None
    true_values: np.ndarray | None = None
    true_rewards: np.ndarray | None = None


@dataclass
class BagEvaluation:
    episodes: list[Episode] = field(default_factory=list)
    unanswered: int = 0  # instructions without a goal_pose (or without a truth)
    topics: dict = field(default_factory=dict)

    def metrics(self) -> dict:
        out = {'n': len(self.episodes), 'unanswered': self.unanswered, 'topics': self.topics}
        if not self.episodes:
            out['md'] = None
            return out
        md = [abs(e.goal[0] - e.truth[0]) + abs(e.goal[1] - e.truth[1]) for e in self.episodes]
        out['md'] = float(np.mean(md))
        out['hit'] = float(np.mean([d == 0 for d in md]))  # the goal_pose is the true goal cell
        full = [
            e
            for e in self.episodes
            if e.values is not None
            and e.true_values is not None
            and e.true_rewards is not None
            and e.values.shape == e.true_values.shape
        ]
        if full and len({e.values.shape for e in full}) == 1:
            pred = np.stack([e.values for e in full])
            true = np.stack([e.true_values for e in full])
            rewards = np.stack([e.true_rewards for e in full])
            terminal = np.zeros(true.shape, bool)
            for t, e in zip(terminal, full):
                t[e.truth] = True
            out['pq'] = float(np.mean(world.policy_quality(pred, true, rewards, terminal)))
            out['mse'] = world.mse(pred, true)
            out['n_value_maps'] = len(full)
        return out


def evaluate_bag(path: str | Path, topics: dict[str, str] | None = None) -> BagEvaluation:
    """Pair instructions, answers and truths in a bag (see the module docstring)."""
    wanted = {**TOPICS, **(topics or {})}
    reader = open_bag(path)
    try:
        available = {c.topic: c.msgtype for c in reader.connections}
        found = resolve_topics(available, wanted)
        missing = [r for r in REQUIRED if r not in found]
        if missing:
            raise ValueError(
                f'{path}: bag has no '
                f'{", ".join(f"{r} topic ({wanted[r]!r}, {MSGTYPES[r]})" for r in missing)}; '
                f'it has: {", ".join(sorted(available)) or "no topics"}'
            )
        store = typestore()
        role_of = {t: r for r, t in found.items()}
        events = []  # (time, role, message)
        try:
            for conn, t, raw in reader.messages(
                [c for c in reader.connections if c.topic in role_of]
            ):
                events.append((t, role_of[conn.topic], store.deserialize_cdr(raw, conn.msgtype)))
        except Exception as exc:  # truncated or corrupt chunks
            raise ValueError(
                f'{path}: bag is truncated or corrupt ({type(exc).__name__}: {exc})'
            ) from exc
    finally:
        reader.close()
    events.sort(key=lambda e: e[0])
    result = BagEvaluation(topics=found)
    latest_map, latest_true, truths = None, {}, []
    pending: dict | None = None  # the latest instruction and what answered it so far

    def finish(p: dict | None) -> None:
        if p is None:
            return
        cells = None
        if p['goal'] is not None and p['truth'] is not None and p['map'] is not None:
            info = p['map'].info
            cells = (
                point_to_cell(p['goal'].pose.position.x, p['goal'].pose.position.y, info),
                point_to_cell(p['truth'].pose.position.x, p['truth'].pose.position.y, info),
            )
        if cells is None or None in cells:
            result.unanswered += 1
            return
        ep = Episode(p['instruction'], *cells)
        if p['values'] is not None:
            ep.values = multiarray_to_map(p['values'])
        if {'true_values', 'true_rewards'} <= set(p['true']):
            ep.true_values = multiarray_to_map(p['true']['true_values'])
            ep.true_rewards = multiarray_to_map(p['true']['true_rewards'])
        result.episodes.append(ep)

    for _, role, msg in events:
        if role == 'map':
            latest_map = msg
        elif role in ('true_values', 'true_rewards'):
            latest_true[role] = msg
        elif role == 'truth':
            truths.append(msg)
        elif role == 'instruction':
            finish(pending)
            pending = {
                'instruction': msg.data,
                'goal': None,
                'truth': None,
                'map': None,
                'values': None,
                'true': {},
            }
        elif pending is None:
            continue
        elif role == 'values' and pending['values'] is None:
            pending['values'] = msg
        elif role == 'goal' and pending['goal'] is None:
            pending.update(
                goal=msg,
                truth=truths[-1] if truths else None,
                map=latest_map,
                true=dict(latest_true),
            )
            truths = []
    finish(pending)
    return result


def cmd_eval_bag(args) -> int:
    topics = {
        role: getattr(args, f'{role}_topic')
        for role in TOPICS
        if getattr(args, f'{role}_topic') is not None
    }
    metrics = evaluate_bag(args.bag, topics).metrics()
    if args.json:
        print(json.dumps({'bag': str(args.bag), **metrics}))
    elif metrics['n'] == 0:
        print(
            f'{args.bag}: no answered instruction with a recorded truth '
            f'({metrics["unanswered"]} unanswered)'
        )
    else:
        line = (
            f'{args.bag}: {metrics["n"]} answered instructions, MD {metrics["md"]:.2f}, '
            f'HIT {metrics["hit"]:.3f}'
        )
        if 'pq' in metrics:
            line += f', PQ {metrics["pq"]:.3f}, MSE {metrics["mse"]:.3f}'
        print(line + f' ({metrics["unanswered"]} unanswered)')
    return 0


def register_cli(sub) -> None:
    p = sub.add_parser('eval-bag', help='score the goals recorded in a rosbag2 bag (MD, PQ, MSE)')
    p.add_argument('bag', help='bag directory (or its .mcap file)')
    for role, name in TOPICS.items():
        p.add_argument(
            f'--{role.replace("_", "-")}-topic',
            default=None,
            help=f'{MSGTYPES[role]} topic (default: {name!r} in any namespace)',
        )
    p.add_argument('--json', action='store_true', help='print exactly one JSON object')
    p.set_defaults(func=cmd_eval_bag)
