# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The Python API's honest answers and tables of one's own, with the shipped default.

Every decline reason on a map made by hand, confidence and alternatives, a table the model
never saw (names, aliases, typos), the generated unanswerable cases, and the calibration
arithmetic against values worked by hand.
"""

import json
import math

from conftest import REPO
import numpy as np
import pytest
from spatial_grounding_ros.core.entities import EntityTable
from spatial_grounding_ros.data.unanswerable import cases, KINDS, REASONS, table_of
from spatial_grounding_ros.grounder import Grounder, REASONS as GROUNDER_REASONS
from spatial_grounding_ros.studies.calibration import (
    expected_calibration_error,
    fit_temperature,
    mean_nll,
)

OFFICE = REPO / 'config' / 'entities_office.yaml'
ROCK, TREE, HOUSE, PUDDLE, STAR = 8, 9, 10, 1, 2


@pytest.fixture(scope='module')
def office() -> Grounder:
    return Grounder.from_checkpoint(entities=OFFICE)


@pytest.fixture(scope='module')
def grounder() -> Grounder:
    return Grounder.from_checkpoint()


def pw_map() -> np.ndarray:
    grid = np.zeros((12, 12), dtype=np.int64)
    grid[3, 4] = ROCK
    grid[5, 5] = TREE
    grid[10, 2] = HOUSE
    grid[7, 7] = STAR
    grid[9:11, 7:10] = PUDDLE
    return grid


def test_a_clear_instruction_is_answered_with_confidence_and_alternatives(grounder):
    g = grounder.ground(pw_map(), 'reach cell two below the rock')
    assert g.reason is None and g.goal == g.best == (5, 4)
    assert 0.5 < g.confidence <= 1
    assert len(g.alternatives) == 3
    scores = [g.confidence] + [p for _, p in g.alternatives]
    assert scores == sorted(scores, reverse=True)
    assert g.best not in [cell for cell, _ in g.alternatives]
    assert g.landmarks == ['rock'] and g.referent == (3, 4)


@pytest.mark.parametrize(
    'instruction, reason',
    [
        ('reach cell two below the heart', 'referent-missing: heart'),
        ('go to the fridge', 'unknown-landmark: fridge'),
        ('reach cell two above the fridge please', 'unknown-landmark: fridge'),
        ('reach cell three below the house', 'off-map'),
        ('reach cell four to the left of the house', 'off-map'),
        ('reach cell two above the star', None),
        # a puddle is costly, not impassable: a goal may lie there (PuddleWorld's human data
        # has goals in puddles); it was declined as goal-on-obstacle before traversal
        ('reach cell two below the star', None),
    ],
)
def test_each_reason_the_map_gives(grounder, instruction, reason):
    g = grounder.ground(pw_map(), instruction)
    assert g.reason == reason
    assert (g.goal is None) == (reason is not None)


def test_several_landmarks_named_as_one_are_ambiguous_unless_something_picks_one(grounder):
    grid = pw_map()
    grid[1, 1] = grid[6, 10] = ROCK
    assert grounder.ground(grid, 'reach cell one below the rock').reason == 'ambiguous: 3 rocks'
    assert grounder.ground(grid, 'reach cell one below the westernmost rock').reason is None
    assert grounder.ground(grid, 'reach the rock closest to the tree').reason is None


def test_an_extreme_two_landmarks_share_is_ambiguous(grounder):
    grid = pw_map()
    grid[1, 1] = grid[1, 8] = ROCK  # two rocks on the top row
    g = grounder.ground(grid, 'reach the northernmost rock')
    assert (g.goal, g.reason) == (None, 'ambiguous: 2 rocks tie as northernmost')
    assert grounder.ground(grid, 'go to the topmost rock').reason_code == 'ambiguous'
    assert grounder.ground(grid, 'reach the westernmost rock').goal == (1, 1)


@pytest.mark.parametrize(
    'instruction, goal',
    [
        # "over" is the verb's: read as an offset, a wall. The couch is solid: the free cell
        # beside it (west and east tie; the first in row-major order)
        ('go over to the couch', (1, 2)),
        ('head to the second square below the couch', (3, 3)),  # one below is a wall
        ('stop right above the refrigerator', (6, 9)),  # no side: one right is off the map
        ("go to the refrigerator's left", (7, 8)),
        ("drive two squares to the couch's right side", (1, 5)),
    ],
)
def test_the_checks_read_the_wording_the_model_reads(instruction, goal):
    table = EntityTable.from_yaml(OFFICE)
    grid = np.zeros((10, 10), dtype=np.int64)
    grid[0, :] = grid[2, 3] = table.index('wall')
    grid[1, 3], grid[7, 9] = table.index('sofa'), table.index('fridge')
    g = Grounder.from_checkpoint(entities=OFFICE).ground(grid, instruction)
    assert (g.reason, g.goal) == (None, goal), g.model_instruction


def test_in_front_of_and_behind_name_no_side_on_a_map():
    table, grid = office_map()
    office = Grounder.from_checkpoint(entities=OFFICE)
    g = office.ground(grid, 'stop in front of the fridge')
    assert (g.goal, g.reason) == (None, 'ambiguous: "in front of" names no side on a map')
    assert office.ground(grid, 'wait behind the couch').reason_code == 'ambiguous'
    assert office.ground(grid, 'go one cell below the fridge').reason is None


def farthest_chair_from_the_fridge(table: EntityTable, grid: np.ndarray) -> tuple[int, int]:
    """Return the office map's chair farthest from its fridge at (7, 8), centre to centre."""
    chairs = np.argwhere(grid == table.index('chair'))
    return tuple(chairs[((chairs - (7, 8)) ** 2).sum(1).argmax()])


def beside(g, landmark: tuple[int, int]) -> bool:
    """Say whether a grounding stops on a cell beside a one-cell landmark, facing it."""
    near = abs(g.goal[0] - landmark[0]) + abs(g.goal[1] - landmark[1]) == 1
    return g.reason is None and near and g.referent == landmark


def test_nearness_to_a_solid_landmark_is_answered_and_furthest_from_not_read_as_closest(
    grounder,
):
    table, grid = office_map()
    office = Grounder.from_checkpoint(entities=OFFICE)
    # a fridge is solid: next to it is a free cell beside it (it was declined as "ambiguous:
    # no side of the fridge is named" before approach goals)
    assert beside(office.ground(grid, 'go next to the fridge'), (7, 8))
    assert beside(office.ground(grid, 'go to the cell beside the fridge'), (7, 8))
    # nearness alone to a landmark a robot may stand on still names no cell
    g = grounder.ground(pw_map(), 'go next to the tree')
    assert (g.goal, g.reason) == (None, 'ambiguous: no side of the tree is named')
    # a side, a count or a kind to pick says which cell
    assert office.ground(grid, 'go next to the fridge on its left side').goal == (7, 7)
    # (a kind to pick is answered, not declined: the nearer chair, 7 columns from the fridge,
    # and with it 6 columns away; the default of f315ee9 landed on the fridge at 7); a chair
    # is solid, so the robot stops beside it
    g = office.ground(grid, 'go to the chair nearest the fridge')
    assert g.best == (8, 1) and beside(g, (8, 1))
    grid[8, 1], grid[8, 2] = 0, table.index('chair')
    g = office.ground(grid, 'go to the chair nearest the fridge')
    assert g.best == (8, 2) and beside(g, (8, 2))
    grid[8, 1], grid[8, 2] = table.index('chair'), 0
    # "furthest from" is no closest: the chair farthest from the fridge, a relation composed
    # over the map's chairs (language/compose.py), the robot beside it
    far = farthest_chair_from_the_fridge(table, grid)
    g = office.ground(grid, 'go to the chair furthest from the fridge')
    assert g.reason is None and beside(g, far)
    said = 'go to the cell in the same row as the sofa and the same column as the fridge'
    assert office.ground(grid, said).reason_code == 'unsupported'


@pytest.mark.parametrize(
    'instruction',
    [
        'go away from the fridge',
        'move away from the couch',
        'get far away from the fridge',
        'take a step back from the fridge',
        'far from the couch',
        'stay clear of the fridge',
        'two cells away from the fridge',
        'the farthest cell from the fridge',
        'go to the furthest point from the couch',
    ],
)
def test_away_from_a_landmark_sends_no_goal_to_it(office, instruction):
    """Words that say where not to be, or a distance with no side, name no cell: declined."""
    table, grid = office_map()
    g = office.ground(grid, instruction)
    assert g.goal is None and g.reason_code in ('unsupported', 'ambiguous'), (g.reason, g.goal)


def test_a_kind_picked_farthest_away_from_a_landmark_is_still_answered(office):
    table, grid = office_map()
    far = farthest_chair_from_the_fridge(table, grid)
    g = office.ground(grid, 'go to the chair farthest away from the fridge')
    assert g.reason is None and beside(g, far)
    # a side and a count away from a landmark is a place
    assert office.ground(grid, 'one cell left away from the fridge').goal == (7, 7)


@pytest.mark.parametrize(
    'instruction',
    ['go north', 'head east', 'go west please', 'go north-west', 'go 3 cells north',
     'move 2 cells to the left', 'go to the south', 'north'],
)
def test_a_direction_alone_is_a_motion_not_a_place(office, instruction):
    """With no landmark, a direction is a move from where the robot is: no cell of the map."""
    table, grid = office_map()
    g = office.ground(grid, instruction)
    assert (g.goal, g.intent, g.reason_code) == (None, 'unsupported', 'unsupported'), g.reason


def test_a_corner_is_a_place_without_a_landmark(office):
    table, grid = office_map()
    assert office.ground(grid, 'go to the bottom right corner').goal == (9, 9)
    assert office.ground(grid, 'go to the top left corner').goal == (1, 0)


@pytest.mark.parametrize(
    'instruction',
    [
        'go to the fridge, then the couch',
        'go to the couch after the fridge',
        'go to the couch after visiting the fridge',
        'go to the couch, but first the fridge',
        'after the fridge, go to the couch',
        'before the couch, go to the fridge',
    ],
)
def test_two_steps_go_in_the_order_meant(office, instruction):
    """Said in either order, the robot goes to the fridge first, then the couch."""
    table, grid = office_map()
    g = office.ground(grid, instruction)
    assert g.intent == 'sequence' and g.reason is None, (g.intent, g.reason)
    assert [s.referent for s in g.steps] == [(7, 8), (4, 3)]


def test_the_nearest_of_several_is_the_one_nearest_the_robot(office):
    """Ground "the nearest chair" as the one nearest the robot; with no robot pose, decline."""
    table, grid = office_map()  # chairs at (8, 1) and (2, 2)
    for said in ('go to the nearest chair', 'the closest chair please'):
        g = office.ground(grid, said)
        assert g.goal is None and g.reason_code == 'ambiguous', (said, g.reason)
        assert beside(office.ground(grid, said, robot_cell=(7, 3)), (8, 1))
        assert beside(office.ground(grid, said, robot_cell=(3, 4)), (2, 2))
    assert beside(office.ground(grid, 'go to the chair nearest the fridge'), (8, 1))
    grid[2, 2] = 0  # one chair left: the nearest is that one, robot or not
    assert beside(office.ground(grid, 'go to the nearest chair'), (8, 1))


@pytest.mark.parametrize(
    'said',
    ['go to the fridge and come back', 'go to the fridge, then return here',
     'please go to the fridge and back', 'go to the fridge, grab a drink and come back'],
)
def test_come_back_is_a_last_step_to_where_the_robot_is(office, said):
    """Go to the fridge, then back to the robot's cell; with no robot pose, decline."""
    table, grid = office_map()
    g = office.ground(grid, said, robot_cell=(5, 5))
    assert (g.intent, g.reason) == ('sequence', None)
    assert beside(g.steps[0], (7, 8)) and g.steps[1].goal == (5, 5)
    g = office.ground(grid, said)
    assert g.goal is None and g.reason.startswith('ambiguous: "back" is where the robot is')
    # back to a landmark is a step to it
    g = office.ground(grid, 'go to the fridge and come back to the couch', robot_cell=(5, 5))
    assert [s.referent for s in g.steps] == [(7, 8), (4, 3)]


def test_a_row_and_a_column_past_the_learned_counts_are_composed(grounder):
    """One landmark's row and another's column, counts past 4: geometry, not the network."""
    grid = pw_map()  # rock (3, 4), tree (5, 5), house (10, 2), star (7, 7)
    g = grounder.ground(grid, 'reach cell 5 below rock and 6 to right of house')
    assert (g.goal, g.reason) == ((8, 8), None)
    g = grounder.ground(grid, 'reach cell one above rock and five to the right of house')
    assert (g.goal, g.reason) == ((2, 7), None)
    g = grounder.ground(grid, 'reach cell 9 below rock and 5 to right of house')
    assert (g.goal, g.reason) == (None, 'off-map')


def test_a_footprint_tie_is_judged_at_the_anchors_the_grounder_uses():
    table, grid = office_map()
    grid[8, 1] = grid[2, 2] = 0
    grid[3, 1] = grid[4:7, 7] = table.index('chair')  # one chair, and one three cells tall
    office = Grounder.from_checkpoint(entities=OFFICE)
    g = office.ground(grid, 'reach the northernmost chair')
    assert g.best == (3, 1) and beside(g, (3, 1))
    # the tall one now spans rows 3-6: taken at its middle (row 4) it is not northernmost,
    # but "above" takes each chair at its top edge, and rows 3 and 3 tie
    grid[3, 7] = table.index('chair')
    g = office.ground(grid, 'reach the northernmost chair')
    assert g.best == (3, 1) and beside(g, (3, 1))
    g = office.ground(grid, 'go to the cell above the northernmost chair')
    assert g.reason == 'ambiguous: 2 chairs tie as northernmost'


def test_a_grounding_less_sure_than_the_minimum_declines():
    strict = Grounder.from_checkpoint(min_confidence=0.999)
    g = strict.ground(pw_map(), 'reach the cell near the tree and the house')
    assert g.goal is None and g.reason_code == 'low-confidence'
    assert g.reason_code in GROUNDER_REASONS
    with pytest.raises(ValueError, match='min_confidence'):
        Grounder.from_checkpoint(min_confidence=1.5)


@pytest.mark.parametrize('size', [10, 32])
@pytest.mark.parametrize('kind', KINDS)
def test_generated_unanswerable_cases_are_declined_with_their_reason(grounder, kind, size):
    table = table_of(kind)  # the obstacle case's: PuddleWorld's and a wall
    if table != grounder.entities:
        grounder = Grounder(grounder.loaded, table)
    found = [grounder.ground(g, t).reason_code for g, t in cases(kind, size, 25, seed=7)]
    assert np.mean([r == REASONS[kind] for r in found]) >= 0.9, found


def office_map() -> tuple[EntityTable, np.ndarray]:
    table = EntityTable.from_yaml(OFFICE)
    grid = np.zeros((10, 10), dtype=np.int64)
    grid[0, :] = table.index('wall')
    grid[4, 3] = table.index('sofa')
    grid[7, 8] = table.index('fridge')
    grid[2, 6] = table.index('coffee_machine')
    grid[8, 1] = grid[2, 2] = table.index('chair')
    return table, grid


@pytest.mark.parametrize(
    'instruction, goal',
    [
        ('reach cell two below the sofa', (6, 3)),
        ('Please go two cells below the couch.', (6, 3)),  # an alias, words of its own
        ('reach cell two below the sfoa', (6, 3)),  # a typo
        ('reach the cell one above the refrigerator', (6, 8)),
        ('reach cell with the espresso maker', (2, 6)),  # an alias of two words
        ('reach cell with the cofee machine', (2, 6)),  # a typo in a name of two words
        ('reach the southernmost chair', (8, 1)),
        ('reach the chairs closest to the sofa', (2, 2)),
    ],
)
def test_a_table_the_model_never_saw_grounds_without_retraining(instruction, goal):
    table, grid = office_map()
    g = Grounder.from_checkpoint(entities=OFFICE).ground(grid, instruction)
    assert (g.reason, g.best) == (None, goal), g.model_instruction
    # a coffee machine and a chair are solid: the robot stops beside them
    assert g.goal == goal if grid[goal] not in table.solid else beside(g, goal)


def test_a_table_of_ones_own_declines_what_it_lacks():
    table, grid = office_map()
    office = Grounder.from_checkpoint(entities=table)
    assert office.ground(grid, 'reach cell two below the printer').reason == (
        'referent-missing: printer'
    )
    assert office.ground(grid, 'reach cell two below the piano').reason == (
        'unknown-landmark: piano'
    )
    with pytest.raises(ValueError, match='outside the office table'):
        office.ground(np.full((4, 4), 99), 'reach the sofa')


def test_expected_calibration_error_by_hand():
    # bin 0.9-1.0: confidences 0.95, 0.95 with one right: |0.95 - 0.5| = 0.45, weight 2/4;
    # bin 0.6-0.7: 0.65, 0.65 both right: |0.65 - 1| = 0.35, weight 2/4
    got = expected_calibration_error([0.95, 0.95, 0.65, 0.65], [1, 0, 1, 1])
    assert got == pytest.approx(0.5 * 0.45 + 0.5 * 0.35)
    assert expected_calibration_error([1.0, 0.0], [1, 0]) == 0


def test_the_fitted_temperature_recovers_the_one_that_drew_the_goals():
    rng = np.random.default_rng(0)
    scored = []
    for _ in range(400):
        flat = rng.normal(0, 1, 20)
        p = np.exp(flat / 0.5)
        scored.append((flat, int(rng.choice(20, p=p / p.sum()))))
    t = fit_temperature(scored)
    assert t == pytest.approx(0.5, rel=0.25)
    assert mean_nll(scored, t) <= mean_nll(scored, 1.0)
    # one map, one goal: the likelihood of a uniform map is log 20 at any temperature
    assert mean_nll([(np.zeros(20), 3)], 0.1) == pytest.approx(math.log(20))


def test_the_ground_command_answers_and_draws_a_map_of_ones_own(tmp_path, capsys):
    from spatial_grounding_ros import cli

    argv = ['ground', '--entities', str(OFFICE), '--map', str(REPO / 'docs/examples/office.txt')]
    png = tmp_path / 'g.png'
    assert cli.main(argv + ['--instruction', 'reach the westernmost chair', '--out', str(png),
                            '--json']) == 0
    got = json.loads(capsys.readouterr().out)
    assert got['best'] == [3, 1] and got['reason'] is None and got['landmarks'] == ['chair']
    assert got['goal'] == [2, 1]  # a chair is solid: the free cell beside it
    assert png.stat().st_size > 10_000
    assert cli.main(argv + ['--instruction', 'reach cell two below the desk', '--json']) == 0
    got = json.loads(capsys.readouterr().out)
    assert got['goal'] is None and got['reason'] == 'ambiguous: 2 desks'
    bad = tmp_path / 'bad.txt'
    bad.write_text('0 1\n2\n')
    assert cli.main(['ground', '--map', str(bad), '--instruction', 'reach the rock']) == 2
    assert 'rows of equal length' in capsys.readouterr().err


@pytest.mark.parametrize(
    'instruction, referents',
    [
        ('go to the fridge and the couch', [(7, 8), (4, 3)]),
        ('visit the coffee machine and the fridge', [(2, 6), (7, 8)]),
        ('please go to the couch and to the fridge', [(4, 3), (7, 8)]),
        ('go to the fridge and go to the coffee machine', [(7, 8), (2, 6)]),
        ('go to the couch, the fridge and the coffee machine', [(4, 3), (7, 8), (2, 6)]),
        ('go to the fridge, then the couch and the coffee machine', [(7, 8), (4, 3), (2, 6)]),
    ],
)
def test_landmarks_joined_by_and_are_visited_in_turn(office, instruction, referents):
    """Visit "the fridge and the couch" in the order said: two places, not the first alone."""
    table, grid = office_map()
    g = office.ground(grid, instruction)
    assert g.intent == 'sequence' and g.reason is None, (g.intent, g.reason)
    assert [s.referent for s in g.steps] == referents


@pytest.mark.parametrize(
    'instruction, goal',
    [
        ('go to the cell between the fridge and the couch', None),
        ('go one above the fridge and one left of the couch', (6, 2)),
        ('go one cell above the fridge and two cells left of the couch', (6, 1)),
        ('go to the fridge and then stop two cells left of it', (7, 6)),
    ],
)
def test_and_inside_one_place_stays_one_place(office, instruction, goal):
    """Keep an "and" that joins the parts of one place ("a row and a column") one place."""
    table, grid = office_map()
    g = office.ground(grid, instruction)
    assert g.intent == 'go', (g.intent, g.reason)
    if goal is not None:
        assert g.goal == goal, (g.goal, g.reason)


@pytest.mark.parametrize(
    'instruction', ['go to the fridge or the couch', 'the couch or the coffee machine please']
)
def test_either_of_two_places_is_asked_back(office, instruction):
    """Decline "the fridge or the couch" as ambiguous: the choice is left open, no guess."""
    table, grid = office_map()
    g = office.ground(grid, instruction)
    assert (g.goal, g.reason_code) == (None, 'ambiguous'), g.reason


@pytest.mark.parametrize(
    'instruction',
    [
        'if the coffee machine is on, go to the couch',
        'go to the fridge unless the door is closed',
        'go to the fridge when the kettle boils',
        'go to the couch only if nobody is sitting there',
        'once the meeting ends go to the coffee machine',
        'go to the fridge as soon as the light turns green',
        'wait until the meeting ends, then go to the couch',
        'if you see the coffee machine, go to the fridge',
    ],
)
def test_a_condition_the_robot_cannot_check_is_declined(office, instruction):
    """The robot cannot tell whether a condition holds, so it must not act as if it did."""
    table, grid = office_map()
    g = office.ground(grid, instruction)
    assert (g.goal, g.intent, g.reason_code) == (None, 'unsupported', 'unsupported'), g.reason
    assert 'condition' in g.reason


@pytest.mark.parametrize(
    'instruction', ['go to the couch if you can', 'when you are ready, go to the couch',
                    'go to the couch if possible', 'whenever you get a chance go to the couch']
)
def test_a_polite_condition_is_no_condition(office, instruction):
    """Read "if you can" as a courtesy, not a condition: the couch is the place."""
    table, grid = office_map()
    assert beside(office.ground(grid, instruction), (4, 3))


@pytest.mark.parametrize(
    'instruction, landmark',
    [
        ('go to the couch and sit down', (4, 3)),
        ('go to the couch and lie down', (4, 3)),
        ('go to the fridge and turn left', (7, 8)),
        ('go to the fridge and slow down', (7, 8)),
        ('go to the fridge then sit down', (7, 8)),
        ('go to the couch, sit down', (4, 3)),
        ('go to the fridge and look around', (7, 8)),
        ('go to the fridge and wait there for two minutes', (7, 8)),
        ('go to the coffee machine and wait until i come back', (2, 6)),
    ],
)
def test_what_to_do_there_does_not_move_the_goal(office, instruction, landmark):
    """Keep the goal of "go to the couch and sit down": "down" is how to sit, not where."""
    table, grid = office_map()
    g = office.ground(grid, instruction)
    assert beside(g, landmark), (instruction, g.goal, g.reason)


@pytest.mark.parametrize(
    'instruction',
    ["don't go to the fridge, go to the couch", 'avoid the fridge and go to the couch',
     "go to the couch, don't go to the fridge", 'go to the couch but not the fridge',
     'go to the couch instead of the fridge', 'go to the couch rather than the fridge',
     'instead of the fridge, go to the couch', 'rather than the fridge go to the couch'],
)
def test_a_place_to_go_beside_a_negated_or_set_aside_one_is_the_goal(office, instruction):
    """Go to the couch when it is said beside the fridge, negated or set aside for it."""
    table, grid = office_map()
    assert beside(office.ground(grid, instruction), (4, 3))


def test_a_negation_with_no_place_to_go_beside_it_is_declined(office):
    table, grid = office_map()
    for negated in ("don't go to the fridge or the couch", 'never go near the fridge'):
        assert office.ground(grid, negated).intent == 'negation', negated


def test_a_slip_of_the_article_is_read_as_meant(office):
    """Read "teh" as "the": the count and side around it still say the cell."""
    table, grid = office_map()
    assert office.ground(grid, 'go two cells left of teh couch').goal == (4, 1)
    assert office.ground(grid, 'if teh lamp is on, go to the couch').intent == 'unsupported'


def test_the_other_of_two_is_asked_back(office):
    """Decline "the other chair": which is the other needs a chair said before."""
    table, grid = office_map()
    for said in ('go to the other chair', 'go to another chair'):
        assert office.ground(grid, said).reason_code == 'ambiguous', said


@pytest.mark.parametrize(
    'instruction, chair',
    [('go to the chair near the couch', (2, 2)), ('go to the chair by the fridge', (8, 1)),
     ('the chair next to the couch', (2, 2)), ('go to the chair close to the fridge', (8, 1))],
)
def test_a_landmark_near_another_is_the_one_nearest_it(office, instruction, chair):
    """Of two chairs, "the chair near the couch" is the one nearest the couch."""
    table, grid = office_map()  # chairs at (8, 1) and (2, 2), couch (4, 3), fridge (7, 8)
    assert beside(office.ground(grid, instruction), chair)
