# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The grounder node's rules, without ROS: what it holds, when it grounds, how a goal is posed.

InstructionHold keeps the latest valid instruction and tells when to ground it: at once when a
map is held, else when a valid map arrives, unless it waited longer than instruction_timeout;
again on a new map only with reground_on_map_change. An instruction that arrives while an older
one still waits to be grounded supersedes it; the older is handed back, so the node can say that
it was dropped. Times are time.monotonic() seconds (wall time, also under use_sim_time).

goal_yaw and goal_stamp say how a goal cell becomes a pose (goal_heading, goal_stamp). The node
(ros/grounder_node.py) keeps the publishers, subscriptions and callbacks, and a lock around a
hold, which is not thread-safe itself.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
import time
from typing import Callable

from .map_geometry import cell_centre

GOAL_HEADINGS = ('auto', 'identity', 'face_referent', 'keep')
GOAL_STAMPS = ('map', 'now')


@dataclass
class Dropped:
    """An instruction the hold let go of without grounding it, and why."""

    text: str
    why: str  # 'superseded', 'expired', 'inactive', 'rejected'

    def message(self, timeout: float) -> str:
        """Say why it went: expired (after `timeout` s with no map), else superseded."""
        if self.why == 'expired':
            return (f'instruction {self.text!r} expired: no valid entity_map within '
                    f'instruction_timeout={timeout:g} s; dropped, send it again')
        return (f'instruction {self.text!r} dropped: a newer instruction came before it was '
                'grounded')


class InstructionHold:
    """The latest valid instruction, whether it still waits to be grounded, and since when."""

    def __init__(self, clock: Callable[[], float] = time.monotonic):
        self.clock = clock
        self.text: str | None = None
        self.pending = False  # not yet handed out for grounding (take)
        self.received = 0.0

    def hold(self, text: str) -> Dropped | None:
        """Hold `text`, waiting to be grounded; return the instruction it supersedes, if any."""
        superseded = Dropped(self.text, 'superseded') if self.pending else None
        self.text, self.pending, self.received = text, True, self.clock()
        return superseded

    def drop(self, why: str) -> Dropped | None:
        """Forget the held instruction; return it if it was still waiting."""
        dropped = Dropped(self.text, why) if self.pending else None
        self.text, self.pending = None, False
        return dropped

    def expired(self, timeout: float) -> bool:
        """Whether a waiting instruction has waited `timeout` seconds or more (0: never)."""
        return self.pending and timeout > 0 and self.clock() - self.received >= timeout

    def expire(self, timeout: float) -> Dropped | None:
        """Drop the waiting instruction if it expired; return it then."""
        return self.drop('expired') if self.expired(timeout) else None

    def on_map(self, reground: bool) -> bool:
        """Take a new valid map: return whether the held instruction is now to be grounded."""
        if self.text is not None and reground:
            self.pending = True
        return self.pending

    def take(self) -> str | None:
        """Return the instruction to ground now (no longer waiting), or None."""
        if not self.pending:
            return None
        self.pending = False
        return self.text


def goal_yaw(
    heading: str,
    cell: tuple[int, int],
    referent: tuple[int, int] | None,
    robot_yaw: float | None,
    info,
    beside: bool = False,
) -> float | None:
    """
    Return the goal's yaw in the map frame for `heading`; None is the identity.

    face_referent: from the goal cell's centre toward the referent's (None when there is none or
    it is the goal cell); keep: the robot's yaw (None before one is known); auto: face_referent
    for a goal `beside` a solid landmark it approaches ("go to the fridge"), else identity.
    `info` is the map's MapMetaData (or anything with its fields).
    """
    if heading not in GOAL_HEADINGS:
        raise ValueError(
            f'goal_heading must be one of {", ".join(GOAL_HEADINGS)}, got {heading!r}'
        )
    if heading == 'auto':
        heading = 'face_referent' if beside else 'identity'
    if heading == 'keep':
        return robot_yaw if robot_yaw is not None and math.isfinite(robot_yaw) else None
    if heading == 'identity' or referent is None or tuple(referent) == tuple(cell):
        return None
    x0, y0, _ = cell_centre(cell, info)
    x1, y1, _ = cell_centre(referent, info)
    return math.atan2(y1 - y0, x1 - x0)


def goal_stamp(rule: str, map_stamp, now: Callable[[], object]):
    """Return the goal's stamp: the map's (`map`) or now() (`now`, called only then)."""
    if rule not in GOAL_STAMPS:
        raise ValueError(f'goal_stamp must be one of {", ".join(GOAL_STAMPS)}, got {rule!r}')
    return now() if rule == 'now' else map_stamp
