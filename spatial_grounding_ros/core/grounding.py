# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""What grounding an instruction gives: a goal or the reason there is none, and the maps."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
import math

import numpy as np

from .footprints import by_distance, ROBOT_UNKNOWN

# the reasons a grounding may decline with (language/checks.py has the structural ones)
REASONS = (
    'referent-missing',
    'unknown-landmark',
    'off-map',
    'ambiguous',
    'unsupported',
    'goal-on-obstacle',
    'unreachable',
    'low-confidence',
    'unreadable',
    'negation',
    'unknown-region',
)


@dataclass
class Grounding:
    """
    One grounded instruction. Maps are (H, W) with row 0 = north.

    `goal` is None when the grounding declines, and `reason` then says why, as a code and
    words ('referent-missing: rock'); `best` is the model's best cell all the same.
    `confidence` is the calibrated chance that `best` is the cell meant; `alternatives` the
    next best cells with theirs.
    """

    instruction: str
    values: np.ndarray  # predicted value map
    relation_map: np.ndarray  # Z1 (the paper's interpretability view is |Z1|)
    goal: tuple[int, int] | None  # (row, col) of the cell to go to; None: declined
    words: list[str]
    attention: list[float] | None  # per word, averaged over cell pairs (t-RNetAttn only)
    unknown_words: list[str]
    best: tuple[int, int] = (0, 0)
    confidence: float = 0.0
    reason: str | None = None
    alternatives: list[tuple[tuple[int, int], float]] = field(default_factory=list)
    landmarks: list[str] = field(default_factory=list)  # the table's names the words named
    # the cell of a named landmark nearest the best cell (a goal can face it), or None; for a
    # goal beside a solid landmark (language/approach.py), the landmark's cell nearest the goal
    referent: tuple[int, int] | None = None
    model_instruction: str = ''  # what the model read: the landmarks in its own names
    # what the instruction asks for (language.reading.INTENTS): 'go' one goal; 'sequence'
    # `steps` in order, `goal` the first's; 'question' no goal, `answer` in words and
    # `referent` the landmark's cell; 'stop', 'negation', 'unsupported' no goal
    intent: str = 'go'
    steps: list['Grounding'] = field(default_factory=list)
    answer: str | None = None
    # the goal stands beside a solid landmark it approaches (`referent`), not on a cell named
    beside: bool = False

    @property
    def reason_code(self) -> str | None:
        """Return the reason's code alone ('referent-missing'), or None."""
        return None if self.reason is None else self.reason.split(':')[0]


def nearest_option(options: list[Grounding], robot_cell) -> Grounding:
    """
    Return of a choice left to nearness ("whichever is closer") the option nearest the robot.

    An option whose landmark the map lacks is none; any other decline declines the choice (the
    declined one might have been the nearer). Without the robot's cell, or with two goals as
    near as each other (footprints.by_distance), the choice declines as ambiguous.
    """
    left = [g for g in options if g.reason_code != 'referent-missing'] or options[:1]
    declined = next((g for g in left if g.goal is None), None)
    if declined is not None:
        return declined
    if robot_cell is None:
        return replace(left[0], goal=None, reason=ROBOT_UNKNOWN)
    far = [math.dist(g.goal, robot_cell) for g in left]
    i, reason = by_distance(far, 'place', 'robot', 'closest')
    return left[i] if reason is None else replace(left[0], goal=None, reason=reason)
