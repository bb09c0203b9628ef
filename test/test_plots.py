# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""The grounding figure (studies/plots.py): what its panels say."""

import numpy as np

from spatial_grounding_ros.core.entities import PUDDLEWORLD
from spatial_grounding_ros.studies.plots import plot_grounding, relation_title


def test_a_goal_the_grammar_placed_says_it_has_no_relation_map(tmp_path):
    """A blank |Z1| panel says why: no network ran (the demo's composed groundings)."""
    assert relation_title(np.zeros((4, 4))) != relation_title(np.eye(4))
    assert 'no network ran' in relation_title(np.zeros((4, 4)))
    assert relation_title(np.eye(4)) == 'relation map |Z1|'
    grid, values = np.zeros((4, 4), dtype=np.int64), np.eye(4)
    for relation in (np.zeros((4, 4)), np.eye(4)):
        png = plot_grounding(tmp_path / f'{relation.sum():.0f}.png', grid, PUDDLEWORLD, values,
                             relation, 'reach the cell', goal=(1, 1))
        assert png.stat().st_size > 0
