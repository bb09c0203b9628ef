# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
What a landmark is to a robot (a table's `traversal`) and approach goals beside solid ones.

The shipped tables' semantics, old tables with the meaning they had, the model's input left as
it was, the geometry of language/approach.py on small maps, and the Grounder: "go to the fridge"
stops beside it, a goal in a puddle is answered, a goal on a wall is not.
"""

from pathlib import Path

import numpy as np
import pytest
from spatial_grounding_ros.core.entities import (
    EntityTable,
    ISI,
    PUDDLEWORLD,
    PUDDLEWORLD_NAMES,
    PUDDLEWORLD_NONUNIQUE,
    PUDDLEWORLD_UNIQUE,
)
from spatial_grounding_ros.data.unanswerable import WALL, WALLED
from spatial_grounding_ros.grounder import Grounder, REASONS
from spatial_grounding_ros.language.approach import (
    approach,
    footprint_of,
    region_sizes,
    side_cells,
    steps_from,
)
from spatial_grounding_ros.language.lexicon import Translation

CONFIG = Path(__file__).parents[1] / 'config'
OFFICE = EntityTable.from_yaml(CONFIG / 'entities_office.yaml')
K = {name: OFFICE.index(name) for name in OFFICE.names}
FURNITURE = ('desk', 'chair', 'printer', 'plant', 'sofa', 'whiteboard', 'fridge',
             'coffee_machine', 'bookshelf', 'lamp', 'trash_can')  # fmt: skip


def legacy(table: EntityTable) -> EntityTable:
    """Return a table as it was written before `traversal`: names and obstacles alone."""
    d = table.to_dict()
    d.pop('traversal', None)
    return EntityTable.from_dict({**d, 'domain': f'old-{table.domain}'})


# --- the entity tables ------------------------------------------------------------------


def test_puddleworlds_puddle_is_costly_and_its_objects_passable():
    table = EntityTable.from_yaml(CONFIG / 'entities_puddleworld.yaml')
    assert table == PUDDLEWORLD
    assert table.traversal_of(0) == 'free' and table.traversal_of(1) == 'costly'
    assert {table.traversal_of(k) for k in range(2, 12)} == {'passable'}
    assert table.obstacles == (1,)  # what the model marks as obstacle, as before
    assert table.never_goal == table.blocks_robot == table.solid == frozenset()


def test_the_offices_furniture_is_solid_and_its_walls_and_unknown_impassable():
    t = OFFICE
    assert {t.traversal_of(K[n]) for n in FURNITURE} == {'solid'}
    assert t.traversal_of(K['door']) == 'passable' and t.traversal_of(K['floor']) == 'free'
    assert t.traversal_of(K['wall']) == t.traversal_of(K['unknown']) == 'impassable'
    assert t.obstacles == (K['wall'], K['unknown'])  # as before: the model's obstacle channel
    assert t.solid == {K[n] for n in FURNITURE}
    assert t.never_goal == t.blocks_robot == t.solid | {K['wall'], K['unknown']}
    assert EntityTable.from_dict(t.to_dict()) == t


def test_isis_blocks_keep_their_meaning_impassable():
    table = EntityTable.from_yaml(CONFIG / 'entities_isi.yaml')
    assert table == ISI and table.obstacles == tuple(range(1, 41))
    assert table.traversal_of(0) == 'free'
    assert table.never_goal == frozenset(range(1, 41)) and not table.solid


def test_an_old_table_loads_with_the_meaning_it_had():
    names = ['deck', 'bulkhead', 'stove', 'rug']
    table = EntityTable.from_dict({'names': names, 'obstacles': [1]})
    assert table.traversal == ()  # nothing listed: each kind takes the unlisted default
    want = ['free', 'impassable', 'passable', 'passable']
    assert [table.traversal_of(k) for k in range(4)] == want
    assert table.never_goal == {1} == set(table.obstacles)
    assert 'traversal' not in table.to_dict() and EntityTable.from_dict(table.to_dict()) == table


def test_a_puddleworld_table_saved_before_traversal_takes_the_shipped_one():
    """A checkpoint's header holds its table as it was written: PuddleWorld's reads as shipped."""
    header = {'domain': 'puddleworld', 'names': list(PUDDLEWORLD_NAMES), 'obstacles': [1],
              'embed_dim': 7}
    assert EntityTable.from_dict(header) == PUDDLEWORLD
    assert Grounder.from_checkpoint().entities.traversal_of(1) == 'costly'


def test_a_table_may_give_traversal_alone_and_its_obstacles_follow():
    table = EntityTable.from_dict({
        'names': ['tiles', 'wall', 'oven', 'spill', 'mat'],
        'traversal': {'wall': 'impassable', 'oven': 'solid', 'spill': 'costly'},
    })
    assert table.obstacles == (1, 3)
    want = ['free', 'impassable', 'solid', 'costly', 'passable']
    assert [table.traversal_of(k) for k in range(5)] == want


@pytest.mark.parametrize(
    'traversal, message',
    [
        ({'oven': 'hot'}, 'each must be one of free, passable'),
        ({'sink': 'solid'}, "traversal names \\['sink'\\]"),
        ({'wall': 'solid'}, 'must be its costly and impassable kinds, but wall is solid'),
        ({'oven': 'costly'}, 'but oven is costly'),
        (['wall'], 'traversal must map a name'),
    ],
)
def test_a_traversal_that_contradicts_the_obstacles_says_so(traversal, message):
    with pytest.raises(ValueError, match=message):
        EntityTable.from_dict({'names': ['tiles', 'wall', 'oven'], 'obstacles': [1],
                               'traversal': traversal})


def test_the_model_reads_every_map_as_before():
    """Traversal changes no bit of what the model reads: Translation and the value map."""
    grid = office_map()
    model = PUDDLEWORLD
    old, new = (Translation(t, model, PUDDLEWORLD_UNIQUE, PUDDLEWORLD_NONUNIQUE)
                for t in (legacy(OFFICE), OFFICE))
    grounders = [Grounder.from_checkpoint(entities=t) for t in (legacy(OFFICE), OFFICE)]
    for text in ('go to the fridge', 'go two cells below the sofa', 'go next to the sofa',
                 'reach the chair closest to the fridge', 'go one cell above the sofa'):
        a, b = old(grid, text), new(grid, text)
        assert np.array_equal(a.grid, b.grid) and a.instruction == b.instruction
        va, vb = (g.ground(grid, text).values for g in grounders)
        assert np.array_equal(va, vb)


# --- approach geometry ------------------------------------------------------------------


def masks(grid: np.ndarray, table: EntityTable = OFFICE):
    stand = np.isin(grid, sorted(table.kinds_that_are('free', 'passable')))
    return stand, ~np.isin(grid, sorted(table.blocks_robot))


def test_the_cells_beside_a_footprint_are_per_side_and_free():
    grid = np.zeros((6, 6), dtype=np.int64)
    grid[2:4, 2:4] = K['fridge']
    grid[1, 2] = K['wall']
    grid[2, 1] = K['unknown']
    grid[4, 3] = K['chair']
    grid[2, 4] = K['door']  # passable: a robot may stop in a doorway
    cells = side_cells(np.argwhere(grid == K['fridge']), masks(grid)[0])
    assert cells == {'north': [(1, 3)], 'south': [(4, 2)], 'west': [(3, 1)],
                     'east': [(2, 4), (3, 4)]}


def test_an_l_shaped_footprints_notch_counts_once():
    grid = np.zeros((5, 5), dtype=np.int64)
    grid[1, 1:4] = grid[2:4, 1] = K['desk']  # an L: its notch (2, 2) borders two cells
    cells = side_cells(np.argwhere(grid == K['desk']), masks(grid)[0])
    everything = [c for side in cells.values() for c in side]
    assert len(everything) == len(set(everything)) and (2, 2) in cells['south']


def test_a_footprint_is_the_landmark_the_cell_is_on_or_the_nearest():
    grid = np.zeros((5, 5), dtype=np.int64)
    grid[0, 0:2] = grid[3, 3] = grid[4, 4] = 9
    assert footprint_of(grid, 9, (0, 1)).tolist() == [[0, 0], [0, 1]]
    assert footprint_of(grid, 9, (2, 2)).tolist() == [[3, 3], [4, 4]]  # touching: one
    assert footprint_of(grid, 9, (2, 2), drawn_over_cells=False).tolist() == [[3, 3]]


def test_steps_go_around_walls_and_stop_at_the_targets():
    through = np.ones((5, 5), dtype=bool)
    through[0:4, 2] = False  # a wall with a gap at the bottom
    assert steps_from(through, (0, 0), [(0, 4), (4, 0)]) == {(4, 0): 4, (0, 4): 12}
    assert steps_from(through, (0, 0), [(9, 9)]) == {}


def test_the_largest_region_counts_and_its_size_is_capped():
    through = np.ones((6, 6), dtype=bool)
    through[:, 2] = False
    assert region_sizes(through, [(0, 0), (0, 5)]) == {(0, 0): 12, (0, 5): 18}
    assert region_sizes(through, [(0, 5)], cap=5) == {(0, 5): 5}


def approach_map() -> np.ndarray:
    """Return a 2x2 fridge in a room, a wall closing its west side off into a pocket."""
    grid = np.zeros((8, 8), dtype=np.int64)
    grid[0, :] = grid[:, 0] = K['wall']
    grid[3:5, 3:5] = K['fridge']
    grid[2:6, 1] = grid[2, 2] = grid[5, 2] = K['wall']  # the pocket: (3, 2) and (4, 2)
    return grid


def test_with_no_robot_the_goal_is_in_the_largest_region_nearest_the_best_cell():
    grid = approach_map()
    fridge = np.argwhere(grid == K['fridge'])
    stand, through = masks(grid)
    goal, referent, others = approach(fridge, stand, through, toward=(4, 3))
    # the west side is a pocket of two cells, nearest the best cell but last
    assert goal == (5, 3) and referent == (4, 3)
    assert others == ((2, 3), (4, 5), (4, 2))
    # north and east tie: the first in row-major order
    assert approach(fridge, stand, through, toward=(3, 4))[0] == (2, 4)


def test_with_a_robot_the_goal_is_the_side_it_reaches_first():
    grid = approach_map()
    fridge = np.argwhere(grid == K['fridge'])
    stand, through = masks(grid)
    goal, referent, others = approach(fridge, stand, through, (3, 3), robot_cell=(3, 7))
    assert goal == (3, 5) and referent == (3, 4)  # east, 2 steps
    assert others == ((2, 4), (5, 4))  # north 4 steps, south 5; the pocket is unreachable
    # from inside the pocket only its side is reachable
    goal, _, others = approach(fridge, stand, through, (3, 3), robot_cell=(4, 2))
    assert goal == (4, 2) and others == ()


def test_a_footprint_with_no_free_side_has_no_goal():
    grid = np.full((5, 5), K['wall'], dtype=np.int64)
    grid[2, 2] = K['fridge']
    stand, through = masks(grid)
    assert approach(np.array([[2, 2]]), stand, through, (2, 2)) == (None, None, ())
    grid[2, 3] = K['floor']
    assert approach(np.array([[2, 2]]), stand, through, (2, 2))[0] is None  # masks are stale
    stand, through = masks(grid)
    assert approach(np.array([[2, 2]]), stand, through, (2, 2))[0] == (2, 3)
    assert approach(np.array([[2, 2]]), stand, through, (2, 2), robot_cell=(0, 0))[0] is None


# --- the Grounder -----------------------------------------------------------------------


@pytest.fixture(scope='module')
def office() -> Grounder:
    return Grounder.from_checkpoint(entities=OFFICE)


def office_map() -> np.ndarray:
    """Return a 10x10 office: a wall on top, a 1x3 sofa under it, a 2x2 fridge, a printer."""
    grid = np.zeros((10, 10), dtype=np.int64)
    grid[0, :] = K['wall']
    grid[1, 1:4] = K['sofa']
    grid[4:6, 4:6] = K['fridge']
    grid[8, 8] = K['printer']
    return grid


def touches(cell, footprint) -> bool:
    return any(abs(cell[0] - r) + abs(cell[1] - c) == 1 for r, c in footprint)


@pytest.mark.parametrize('robot', [None, (9, 0), (1, 9)])
def test_go_to_the_fridge_stops_on_a_free_cell_beside_it_facing_it(office, robot):
    grid = office_map()
    fridge = [tuple(c) for c in np.argwhere(grid == K['fridge'])]
    g = office.ground(grid, 'go to the fridge', robot_cell=robot)
    assert g.reason is None and g.best in fridge  # the model's cell is the fridge's
    assert grid[g.goal] == K['floor'] and touches(g.goal, fridge)
    assert g.referent in fridge and touches(g.goal, [g.referent])
    # the other three sides, one cell each (the fridge: rows 4-5, columns 4-5)
    cells = [g.goal] + [c for c, _ in g.alternatives]
    sides = {'n' if r < 4 else 's' if r > 5 else 'w' if c < 4 else 'e' for r, c in cells}
    assert all(touches(c, fridge) for c in cells) and len(cells) == len(sides) == 4
    if robot == (9, 0):  # the fridge's south-west: south or west, four steps either way
        assert g.goal in ((5, 3), (6, 4))
    if robot == (1, 9):
        assert g.goal in ((3, 5), (4, 6))


def test_go_next_to_the_sofa_is_answered_beside_it(office):
    grid = office_map()
    sofa = [tuple(c) for c in np.argwhere(grid == K['sofa'])]
    for text in ('go next to the sofa', 'stop beside the couch', 'wait by the sofa'):
        g = office.ground(grid, text)
        assert g.reason is None, (text, g.reason)
        assert grid[g.goal] == K['floor'] and touches(g.goal, sofa) and g.referent in sofa
    assert touches(office.ground(grid, 'stop by the printer').goal, [(8, 8)])


def test_an_offset_from_a_solid_landmark_is_from_its_edge_as_before(office):
    grid = office_map()
    before = Grounder.from_checkpoint(entities=legacy(OFFICE))
    for text in ('go two cells below the sofa', 'go one cell to the left of the fridge',
                 'stop two cells above the printer'):
        g, old = office.ground(grid, text), before.ground(grid, text)
        assert (g.goal, g.reason, g.referent) == (old.goal, old.reason, old.referent), text
        assert g.goal is not None
    assert office.ground(grid, 'go two cells below the sofa').goal == (3, 2)


def test_a_goal_on_a_wall_or_on_furniture_is_still_declined(office):
    grid = office_map()
    assert office.ground(grid, 'go one cell above the sofa').reason == 'goal-on-obstacle'
    assert office.ground(grid, 'go two cells below the fridge').goal == (7, 4)
    grid[7, 4] = K['chair']  # a goal on furniture not named: never a goal cell
    assert office.ground(grid, 'go two cells below the fridge').reason == 'goal-on-obstacle'


def test_a_landmark_no_robot_can_reach_declines(office):
    grid = office_map()
    grid[3:7, 3:7] = K['wall']
    grid[4:6, 4:6] = K['fridge']
    g = office.ground(grid, 'go to the fridge')
    assert (g.goal, g.reason) == (None, 'unreachable: fridge') and 'unreachable' in REASONS
    grid[2:8, 2:8] = K['wall']  # a free ring around it, walled in
    grid[3:7, 3:7] = K['floor']
    grid[4:6, 4:6] = K['fridge']
    assert touches(office.ground(grid, 'go to the fridge').goal, [(4, 4), (5, 5)])
    g = office.ground(grid, 'go to the fridge', robot_cell=(9, 9))  # outside: never gets there
    assert (g.goal, g.reason) == (None, 'unreachable: fridge')
    assert office.ground(grid, 'go to the fridge', robot_cell=(3, 5)).goal == (3, 5)


def test_next_to_a_solid_landmark_the_map_lacks_is_referent_missing(office):
    grid = office_map()
    grid[grid == K['fridge']] = K['floor']
    g = office.ground(grid, 'go next to the fridge', robot_cell=(9, 9))
    assert (g.goal, g.reason) == (None, 'referent-missing: fridge')


def test_a_robot_cell_off_the_map_is_refused(office):
    with pytest.raises(ValueError, match='off the 10x10 map'):
        office.ground(office_map(), 'go to the fridge', robot_cell=(10, 0))
    with pytest.raises(ValueError, match='robot_cell must be'):
        office.ground(office_map(), 'go to the fridge', robot_cell='here')


def test_a_puddleworld_goal_in_a_puddle_is_answered_and_on_a_wall_declined():
    grid = np.zeros((10, 10), dtype=np.int64)
    grid[3, 4], grid[5, 4] = PUDDLEWORLD.index('star'), PUDDLEWORLD.index('puddle')
    g = Grounder.from_checkpoint().ground(grid, 'reach cell two below the star')
    assert (g.goal, g.reason) == ((5, 4), None)
    grid[5, 4] = WALL
    walled = Grounder.from_checkpoint(entities=WALLED)
    g = walled.ground(grid, 'reach cell two below the star')
    assert (g.goal, g.reason) == (None, 'goal-on-obstacle')
