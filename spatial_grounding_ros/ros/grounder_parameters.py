# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""The grounder node's parameters, each with its default, description and range or choices."""

from __future__ import annotations

from . import convert
from .node_support import Param
from ..core.instruction_hold import GOAL_STAMPS
from ..grounder import DEFAULT_CHECKPOINT, MIRROR_AVERAGE_BELOW, MIRROR_AVERAGE_CELLS

PARAMETERS = (
    Param(
        'checkpoint',
        DEFAULT_CHECKPOINT,
        'packaged checkpoint name (spatial_grounding_ros/checkpoints/<name>.pt) or a path '
        'to a .pt; loaded on configure',
        read_only=True,
        non_empty=True,
    ),
    Param(
        'entity_table',
        'entities_office.yaml',
        'entity table naming the entity_map cell values: a file in config/ or a path (the '
        "entity mapper's default is the same; PuddleWorld maps need entities_puddleworld.yaml); "
        'any table for a PuddleWorld model (its landmarks are read by role), only its own for '
        'another model (checked on configure)',
        read_only=True,
        non_empty=True,
    ),
    Param(
        'max_cells',
        1024 * 1024,
        'larger entity maps are rejected (work and memory grow with the cells: a 1024x1024 '
        'map grounds in about a second, peak RSS under 1 GB; docs/benchmarks.md)',
        low=1,
        high=4096 * 4096,
    ),
    Param(
        'mirror_average_cells',
        MIRROR_AVERAGE_CELLS,
        'maps of at most this many cells may be grounded with their three mirror images too and '
        'the value maps averaged (mirror_average_below says when); 0: never',
        low=0,
        high=4096 * 4096,
    ),
    Param(
        'mirror_average_below',
        MIRROR_AVERAGE_BELOW,
        'a map grounded alone whose best cell has a calibrated probability below this is '
        'grounded with its mirror images too (steadier goals where the model is unsure, at '
        'twice the work or more; docs/benchmarks.md); 1: every map',
        low=0.0,
        high=1.0,
    ),
    Param('max_instruction_chars', 500, 'longer instructions are rejected', low=1, high=100000),
    Param(
        'max_pending_requests',
        16,
        'ground_instruction requests in flight at once (one grounds, the rest wait for it); '
        'one more is refused at once with reason busy',
        read_only=True,
        low=1,
        high=256,
    ),
    Param(
        'reground_on_map_change',
        False,
        'ground the held instruction again on each new entity_map (false: a new map is used '
        'by the next instruction, so Nav2 does not get a new goal on every map update)',
    ),
    Param(
        'min_confidence',
        0.1,
        'decline (no goal; a WARN diagnostic, reason low-confidence) when the calibrated '
        'probability of the best cell is below this (0.1, the API default: no near-zero goal '
        'is sent, the suite and the human splits stay answered; docs/honest-answers.md); 0 '
        'never declines for confidence',
        low=0.0,
        high=1.0,
    ),
    Param(
        'instruction_timeout',
        30.0,
        'seconds an instruction may wait for a valid entity_map; then it is dropped with a '
        'WARN diagnostic, so a later map never grounds it; 0 = wait forever',
        low=0.0,
        high=86400.0,
    ),
    Param(
        'goal_heading',
        'auto',
        'goal orientation: auto (face_referent for a goal beside a solid landmark it '
        'approaches, "go to the fridge"; identity otherwise), identity (the map frame\'s +x), '
        "face_referent (toward the named landmark's cell nearest the goal), keep (the yaw of "
        'the latest robot_pose)',
        choices=convert.GOAL_HEADINGS,
    ),
    Param(
        'goal_stamp',
        'map',
        "goal_pose stamp: map = the entity map's stamp (where the map was), now = the node "
        "clock's time of grounding",
        choices=GOAL_STAMPS,
    ),
    Param(
        'value_map_encoding',
        'display',
        'value_map cells: display = best cell 100, worst 0 (a colour ramp); cost = best 0, '
        'worst 100 (a costmap colour scheme; not an input for a Nav2 costmap layer)',
        choices=convert.VALUE_MAP_ENCODINGS,
    ),
    Param(
        'default_frame_id',
        'map',
        "frame of the outputs when the entity_map's header.frame_id is empty",
        non_empty=True,
    ),
    Param(
        'torch_threads',
        1,
        'torch intra-op threads (process-wide), set on configure: 1 keeps latency steady '
        "next to other busy processes, 0 leaves torch's default (all cores)",
        read_only=True,
        low=0,
        high=1024,
    ),
    Param(
        'autostart',
        True,
        'configure and activate at start-up (false: wait for a lifecycle manager on '
        '<node>/change_state)',
        read_only=True,
    ),
)
