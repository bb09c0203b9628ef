# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The one reading of an instruction (language/reading.py), as a robot's user talks to it.

Each wording here was written as a person says it to a robot, before looking at how the
reader takes it; the cells are worked out by hand on the office map below.
"""

import numpy as np
import pytest

from spatial_grounding_ros.grounder import Grounder
from spatial_grounding_ros.language.reading import INTENTS
from spatial_grounding_ros.language.units import digits, in_cells

OFFICE = 'config/entities_office.yaml'


@pytest.fixture(scope='module')
def office():
    return Grounder.from_checkpoint(entities=OFFICE, cell_size=0.5)


@pytest.fixture(scope='module')
def puddleworld():
    return Grounder.from_checkpoint()


def office_map(grounder) -> np.ndarray:
    """Return a 12x12 office: walls on the top row and left column, two chairs."""
    names = grounder.entities.names
    grid = np.zeros((12, 12), dtype=np.int64)
    grid[0, :] = grid[:, 0] = names.index('wall')
    for name, cell in (('fridge', (3, 3)), ('sofa', (8, 6)), ('desk', (5, 9)),
                       ('chair', (2, 8)), ('chair', (9, 2))):  # fmt: skip
        grid[cell] = names.index(name)
    return grid


def beside(cell):
    """Return the expectation of a goal beside a solid landmark at `cell` (approach goals)."""
    return ('beside', cell)


def lands(result, goal) -> bool:
    """Say whether a grounding's goal is `goal`, or beside the landmark `beside(cell)` names."""
    if isinstance(goal, tuple) and goal[0] == 'beside':
        cell = goal[1]
        return result.goal is not None and result.referent == cell and (
            abs(result.goal[0] - cell[0]) + abs(result.goal[1] - cell[1]) == 1
        )
    return result.goal == goal


@pytest.mark.parametrize(
    'text, intent',
    [
        ('stop', 'stop'),
        ('Stop!', 'stop'),
        ('halt', 'stop'),
        ('cancel that', 'stop'),
        ('never mind', 'stop'),
        ('robot, stop right there please', 'stop'),
        ('where is the fridge?', 'question'),
        ('is there a printer?', 'question'),
        ('hey robot, can you see the sofa?', 'question'),
        ('which way to the desk', 'question'),
        ("don't go to the fridge", 'negation'),
        ('do not go near the sofa', 'negation'),
        ('avoid the desk', 'negation'),
        ('anywhere but the fridge', 'negation'),
        ('never drive to the sofa', 'negation'),
        ("don't go to the fridge, the sofa", 'negation'),  # both, or a correction: unsure
        ('not the fridge or the sofa', 'negation'),
        ('follow me', 'unsupported'),
        ('come here', 'unsupported'),
        ('turn left', 'unsupported'),
        ('go back', 'unsupported'),
        ('go there', 'unsupported'),
        ('go up two', 'unsupported'),
        ('go to the fridge and then the sofa', 'sequence'),
        ('first the desk, then two cells below the fridge', 'sequence'),
        ('go to the fridge after that the desk', 'sequence'),
        ('can you go to the fridge?', 'go'),
        ('could you please drive two cells below the sofa?', 'go'),
        ('the desk, no wait, the fridge', 'go'),
        ('go two cells left of the sofa', 'go'),
    ],
)
def test_each_intent_is_read(office, text, intent):
    assert intent in INTENTS
    result = office.ground(office_map(office), text)
    assert result.intent == intent, (text, result.intent, result.reason)
    if intent not in ('go', 'sequence'):
        assert result.goal is None  # a stop, a question or a decline never sends a goal
    if intent in ('negation', 'unsupported'):
        assert result.reason.startswith(intent)


def test_a_question_answers_in_words_and_cell(office):
    grid = office_map(office)
    where = office.ground(grid, 'where is the fridge?')
    assert where.goal is None and where.referent == (3, 3) and 'fridge' in where.answer
    missing = office.ground(grid, 'is there a printer?')
    assert missing.goal is None and missing.referent is None and 'no printer' in missing.answer
    # a landmark no kind of the table is: said as such, not "which landmark?"
    for text, word in (('where is the piano?', 'piano'), ('where is the oven?', 'oven')):
        unknown = office.ground(grid, text)
        assert unknown.intent == 'question' and unknown.goal is None
        assert unknown.answer == f'no landmark I know of is called "{word}"'
    assert 'which landmark' in office.ground(grid, 'where am I?').answer


def test_a_sequence_grounds_each_step_in_order(office):
    text = 'go two cells below the sofa, then one above the desk'
    result = office.ground(office_map(office), text)
    assert result.intent == 'sequence'
    assert [s.goal for s in result.steps] == [(10, 6), (4, 9)]
    assert result.goal == (10, 6)  # the first step's: the node sends it first


@pytest.mark.parametrize(
    'text',
    ['go to the fridge before the sofa', 'visit the fridge before you go to the sofa',
     'go to the sofa after the fridge'],
)
def test_before_and_after_order_the_steps(office, text):
    result = office.ground(office_map(office), text)
    assert result.intent == 'sequence', (text, result.reason)
    assert [s.referent for s in result.steps] == [(3, 3), (8, 6)]


@pytest.mark.parametrize(
    'text, goal',
    [
        ('go one above the sofa and one to the left', (7, 5)),
        ('a cell below the fridge and to the right', (4, 4)),
        ('one below the fridge and one over to the left', (4, 2)),  # "over" is no side here
        ('end up two cells below the sofa', (10, 6)),  # nor is the verb's "up"
        ('the 2nd cell below the fridge', (5, 3)),
        ('the 3rd square to the left of the desk', (5, 6)),
    ],
)
def test_offsets_said_around_the_landmark_and_as_ordinals(office, text, goal):
    assert office.ground(office_map(office), text).goal == goal


@pytest.mark.parametrize(
    'text', ['go one above the sofa and two below', 'two left of the fridge and one to the right']
)
def test_steps_to_both_sides_of_one_landmark_decline(office, text):
    result = office.ground(office_map(office), text)
    assert result.goal is None and 'opposite sides' in result.reason, (text, result.reason)


@pytest.mark.parametrize('text', ['go to the leftmost object', 'one below the second object'])
def test_a_pick_of_no_kind_declines(office, text):
    result = office.ground(office_map(office), text)  # it sent the network's guess at 0.12
    assert result.goal is None and 'names no kind' in result.reason, (text, result.reason)


def test_a_step_said_of_the_landmark_before_it(office):
    grid = office_map(office)
    two = office.ground(grid, 'go one above the sofa, then two below it')
    assert two.intent == 'sequence' and [s.goal for s in two.steps] == [(7, 6), (10, 6)]
    for text in ('go to the sofa, then two below it', 'go over to the sofa, then end up two '
                 'below it'):  # where the robot ends up
        one = office.ground(grid, text)
        assert one.intent == 'go' and one.goal == (10, 6), text


def test_halfway_to_a_landmark_is_from_the_robot(office):
    grid = office_map(office)
    assert office.ground(grid, 'go halfway to the fridge', robot_cell=(7, 3)).goal == (5, 3)
    unknown = office.ground(grid, 'go halfway to the fridge')
    assert unknown.goal is None and unknown.reason.startswith('ambiguous: said of the robot')


@pytest.mark.parametrize('cell_size, goal', [(1.0, None), (0.5, (6, 3)), (0.05, (6, 3))])
def test_an_even_gap_is_half_a_cell_off_on_a_fine_map(office, cell_size, goal):
    """Robot (8, 3), fridge (3, 3): the middle cell nearer the robot where the map is fine."""
    result = office.ground(
        office_map(office), 'go halfway to the fridge', cell_size=cell_size, robot_cell=(8, 3)
    )
    assert result.goal == goal, result.reason
    if goal is None:
        assert 'an even gap' in result.reason


def test_which_of_a_kind_said_after_it_or_left_to_the_robot(office):
    grid = office_map(office)  # chairs at (2, 8) and (9, 2)
    for text in ('go to the chair on the right', 'go to the chair, the one at the top'):
        assert lands(office.ground(grid, text), beside((2, 8))), text
    assert lands(office.ground(grid, 'go to any chair', robot_cell=(8, 3)), beside((9, 2)))
    assert office.ground(grid, 'go to either chair').reason.startswith('ambiguous: said of')


@pytest.mark.parametrize(
    'text',
    [
        'go to the fridge or the desk, whichever is closer',
        'go to the closer of the fridge and the desk',
        'head to the nearest of the desk and the fridge',
        'whichever is nearer to you, the fridge or the desk',
    ],
)
def test_a_choice_left_to_nearness_is_the_landmark_nearest_the_robot(office, text):
    """Fridge (3, 3), desk (5, 9): from (10, 10) the desk, from (3, 5) the fridge."""
    grid = office_map(office)
    assert lands(office.ground(grid, text, robot_cell=(10, 10)), beside((5, 9)))
    assert lands(office.ground(grid, text, robot_cell=(3, 5)), beside((3, 3)))
    unknown = office.ground(grid, text)  # nearer to what: the robot's cell is not known
    assert unknown.goal is None
    assert unknown.reason == 'ambiguous: said of the robot, whose cell is not known'


def test_options_as_near_as_each_other_decline():
    from spatial_grounding_ros.core.grounding import Grounding, nearest_option

    zeros = np.zeros((3, 3), dtype=np.float32)
    fridge, desk = (Grounding('x', zeros, zeros, goal, [], None, []) for goal in ((0, 0), (2, 2)))
    tie = nearest_option([fridge, desk], (1, 1))
    assert tie.goal is None and tie.reason == 'ambiguous: 2 places tie as nearest from the robot'
    assert nearest_option([fridge, desk], (0, 1)) is fridge
    assert nearest_option([fridge, desk], (2, 1)) is desk


def test_a_choice_by_nearness_of_a_kind_or_a_missing_landmark(office):
    grid = office_map(office)  # chairs at (2, 8) and (9, 2)
    chair = office.ground(grid, 'the chair or the fridge, whichever is closer', robot_cell=(9, 9))
    assert lands(chair, beside((9, 2)))
    # a landmark the map lacks is no option; one the table lacks is a word not understood
    door = office.ground(grid, 'the door or the desk, whichever is nearer', robot_cell=(1, 1))
    assert lands(door, beside((5, 9)))
    # no choice left to nearness: offered, declined; listed, a sequence; a place, the network's
    offered = office.ground(grid, 'go to the fridge or the desk', robot_cell=(10, 10))
    assert offered.goal is None and offered.reason.startswith('ambiguous: one place or another')
    listed = office.ground(grid, 'go to the fridge and the desk', robot_cell=(10, 10))
    assert listed.intent == 'sequence'


@pytest.mark.parametrize(
    'text, referents',
    [
        ('go to the fridge, grab a drink, and bring it to the sofa', [(3, 3), (8, 6)]),
        ('pick up the cup from the fridge and bring it to the desk', [(3, 3), (5, 9)]),
        ('get a soda from the fridge', [(3, 3)]),  # "soda" is no typo of "sofa" here
        ('take the box from the sofa to the fridge', [(8, 6), (3, 3)]),
    ],
)
def test_a_fetch_goes_where_things_are_taken_from_and_to(office, text, referents):
    result = office.ground(office_map(office), text)
    got = [s.referent for s in result.steps] if result.steps else [result.referent]
    assert got == referents, (text, result.reason)


def test_bring_me_comes_back_to_the_robot(office):
    result = office.ground(office_map(office), 'bring me a cup from the desk', robot_cell=(7, 2))
    assert result.intent == 'sequence' and result.steps[-1].goal == (7, 2)


def test_a_superlative_in_two_words(puddleworld):
    grid = np.zeros((10, 10), dtype=np.int64)
    grid[2, 1] = grid[5, 4] = grid[8, 7] = 11  # three horses
    assert puddleworld.ground(grid, 'go to second most western horse .').goal == (5, 4)
    assert puddleworld.ground(grid, 'go to the most western horse').goal == (2, 1)


def test_a_one_reference_then_is_no_sequence(puddleworld):
    """Human PuddleWorld: "one up then one left from the spade" is one place, not two steps."""
    grid = np.zeros((10, 10), dtype=np.int64)
    grid[5, 5] = 6  # spade
    result = puddleworld.ground(grid, 'reach cell one up then one left from the spade')
    assert result.intent == 'go' and result.goal == (4, 4)


@pytest.mark.parametrize(
    'text, goal',
    [
        ('the desk, no wait, the fridge', beside((3, 3))),
        ('two cells below the fridge, sorry, I mean the sofa', beside((8, 6))),
        ('go one left of the sofa, sorry, I mean one right of it', (8, 7)),
        ('go to the fridge, not the sofa', beside((3, 3))),
        ('not the sofa, the fridge', beside((3, 3))),
        ("don't go to the desk but the sofa", beside((8, 6))),
    ],
)
def test_a_self_correction_means_the_last_place_said(office, text, goal):
    assert lands(office.ground(office_map(office), text), goal)


@pytest.mark.parametrize(
    'text',
    [
        'one cell abvoe the sofa',
        'one cell obove the sofa',
        'one cell aboev the sofa',
    ],
)
def test_a_misspelt_direction_is_read_as_meant(office, text):
    assert office.ground(office_map(office), text).goal == (7, 6)


@pytest.mark.parametrize(
    'text, goal',
    [
        ('two cells undr the sofa', (10, 6)),
        ('two cells wset of the sofa', (8, 4)),
        ('two cells to the rigth of the sofa', (8, 8)),
        ('go to the fridgee', beside((3, 3))),
        ('two cells to the left of the sfoa', (8, 4)),
        ('go tow cells right of the sofa', (8, 8)),  # a count before a unit, not "top"
        ('go 2 the fridge', beside((3, 3))),  # a texter's "to"
    ],
)
def test_misspellings_of_relations_and_names(office, text, goal):
    assert lands(office.ground(office_map(office), text), goal)


def test_a_word_not_understood_where_it_changes_the_goal_declines(office):
    grid = office_map(office)
    result = office.ground(grid, 'two cells xqzv of the sofa')
    assert result.goal is None and result.reason_code == 'unreadable'
    assert 'xqzv' in result.reason
    assert office.ground(grid, 'go to the fr dge').reason_code == 'unreadable'
    assert office.ground(grid, 'go xqz cells left of the sofa').reason == 'unreadable: "xqz"'
    # before one unit an unknown word is no count (one cell's is a word known): noise
    assert office.ground(grid, 'go eventually tile left of the sofa').goal == (8, 5)
    # filler and politeness never matter
    assert office.ground(grid, 'um okay robot kindly go two cells below the sofa thanks').goal == (
        10, 6
    )


@pytest.mark.parametrize(
    'text, cells',
    [
        ('6 feet north of the lamp', '4 north of the lamp'),  # 1.83 m at 0.5 m: 4 cells
        ('two yards south of it', '4 south of it'),
        ('a metre and a half east', '3 east'),
        ('one and a half metres east', '3 east'),
        ('half a metre above', '1 above'),
        ('1.5 m left', '3 left'),
        ('50 cm north', '1 north'),
        ('150 centimetres north', '3 north'),
    ],
)
def test_lengths_in_units_people_use(text, cells):
    assert in_cells(digits(text), 0.5) == cells


def test_vague_amounts_are_a_side_and_a_couple_is_two(office):
    grid = office_map(office)  # the sofa at (8, 6)
    assert office.ground(grid, 'go a bit left of the sofa').goal == (8, 5)
    assert office.ground(grid, 'go slightly above the sofa').goal == (7, 6)
    assert office.ground(grid, 'go a couple of cells left of the sofa').goal == (8, 4)


def test_number_words_past_three_become_digits_and_small_ones_stay_words():
    assert digits('go six cells below the rock') == 'go 6 cells below the rock'
    assert digits('go twenty one cells left') == 'go 21 cells left'
    assert digits('go two cells below the rock') == 'go two cells below the rock'


def test_one_reading_for_checks_and_model(puddleworld):
    """With the star in column 0, both wordings of one cell left of it are off the map."""
    grid = np.zeros((10, 10), dtype=np.int64)
    grid[4, 0] = 2
    read = set()
    for text in ('reach one to the left of the star', 'reach the star and one to its left'):
        result = puddleworld.ground(grid, text)
        assert result.goal is None and result.reason == 'off-map', text
        read.add(result.model_instruction)
    assert len(read) == 1, read  # the network reads one wording of both


@pytest.mark.parametrize(
    'text, goal',
    [
        ('Meet me at the sofa. It is across the street from the desk.', beside((8, 6))),
        ("I'm in the kitchen area. Meet me at the fridge. It's across from the sofa.",
         beside((3, 3))),
        ("There's a chair by the door; please wait one cell right of the sofa", (8, 7)),
        ('go down the hall to the fridge', beside((3, 3))),
        ('walk across the room to the sofa', beside((8, 6))),
        ('head along the corridor and go two cells below the sofa', (10, 6)),
    ],
)
def test_long_descriptions_and_ordinary_nouns(office, text, goal):
    assert lands(office.ground(office_map(office), text), goal)


def test_only_the_referents_slot_can_be_unknown(office):
    grid = office_map(office)
    meet = office.ground(grid, 'Meet me at the bakery on the corner. It is across from the desk.')
    assert meet.goal is None and meet.reason == 'unknown-landmark: bakery'
    piano = office.ground(grid, 'go two cells below the piano near the fridge')
    assert piano.reason == 'unknown-landmark: piano'


@pytest.mark.parametrize(
    'text, word',
    [
        ('go to the circle', 'circle'),
        ('go to the box', 'box'),
        ('two cells below the tree', 'tree'),
    ],
)
def test_the_models_own_names_are_no_landmarks_of_another_table(office, text, word):
    result = office.ground(office_map(office), text)
    assert result.goal is None and result.reason == f'unknown-landmark: {word}'


@pytest.mark.parametrize(
    'text, word',
    [
        ('go to the oven', 'oven'),  # one letter from "over"
        ('please go near the oven', 'oven'),
        ('go to the even', 'even'),  # from "seven"
        ('take me to a tower', 'tower'),  # from "lower"
    ],
)
def test_a_name_is_no_typo_of_a_relation_word_or_a_count(office, text, word):
    """Where a landmark's name goes, a word is read as a side or a cell at most."""
    result = office.ground(office_map(office), text)
    assert result.goal is None and result.reason == f'unknown-landmark: {word}'


def test_a_misspelt_side_where_a_name_goes_is_the_side(office):
    assert office.ground(office_map(office), 'go to the lfet of the sofa').goal == (8, 5)
    assert office.ground(office_map(office), 'one cell to the rigth of the sofa').goal == (8, 7)


def test_a_common_english_word_is_no_typo_of_a_name(office):
    """Read "hall" as a hall, though it is one letter from "wall"."""
    assert office.lexicon.mentions('go down the hall') == []
    assert [m.kind for m in office.lexicon.mentions('go to the fridgee')] == [
        office.entities.index('fridge')
    ]


def test_every_generator_family_reads_back_as_the_place_it_names(puddleworld):
    """
    The round trip of the generator's instructions through the reading.

    Each generated instruction reads as one `go` place with no word left unread and no
    reason to decline; an offset family's reading gives back the offset the generator
    rendered (goal minus its landmark's cell), an extreme's its extreme word, and the network
    reads the words the checks read.
    """
    from spatial_grounding_ros.data.generator import FAMILIES, FAMILY_OFFSETS, sample
    from spatial_grounding_ros.language.checks import EXTREME_SIDES, mention_offsets

    rng = np.random.default_rng(0)
    reader = puddleworld.reader
    for family in FAMILIES:
        for _ in range(12):
            grid, text, goal = sample(rng, family, 10)
            command = reader.read(text)
            assert command.intent == 'go' and len(command.steps) == 1, text
            ref = command.reference
            assert ref.reason is None and ref.unknown_words == (), text
            assert ref.mentions, text
            names = {m.kind: puddleworld.entities.names[m.kind] for m in ref.mentions}
            assert ref.model_words(names)[0] == list(ref.words), text
            if family in FAMILY_OFFSETS:
                (m, offset), = mention_offsets(list(ref.words), list(ref.mentions))
                cell = np.argwhere(grid == m.kind)[0]
                assert offset == (goal[0] - cell[0], goal[1] - cell[1]), text
            if family.startswith('extreme'):
                assert set(ref.words) & set(EXTREME_SIDES), text


@pytest.mark.parametrize(
    'text, goal',
    [
        ('place the object under the rock', (8, 8)),
        ('put the cup below the rock', (8, 8)),  # "cup" is no typo of "up" here
        ('set it down below the horse', (5, 6)),
        ('drop it under the star', (2, 1)),
        ('place the object directly beneath the heart', (5, 3)),
        ('could you put the box two cells left of the horse', (4, 4)),
        ('can you place it under the star?', (2, 1)),
        ('put the object on the rock', (7, 8)),
    ],
)
def test_a_placing_goes_where_the_thing_is_put(puddleworld, text, goal):
    grid = np.zeros((10, 10), dtype=np.int64)
    grid[4, 3], grid[4, 6], grid[7, 8], grid[1, 1] = 5, 11, 8, 2  # heart, horse, rock, star
    result = puddleworld.ground(grid, text)
    assert result.intent == 'go' and result.goal == goal, (text, result.reason)


@pytest.mark.parametrize(
    'text, goals',
    [
        ('put the mug in the fridge', [beside((3, 3))]),
        ('set the bag down next to the desk', [beside((5, 9))]),
        ('take the cup from the desk and put it in the fridge', [beside((5, 9)), beside((3, 3))]),
        ('go to the sofa and set it down', [beside((8, 6))]),  # on arrival: no place
        ('place the box around the fridge', [beside((3, 3))]),  # a place the grammar lacks
        ('put the left cup on the desk', [beside((5, 9))]),  # "left" is the cup's, no side
        ('put the top book on the sofa', [beside((8, 6))]),
        ('place the right box beside the sofa', [beside((8, 6))]),
    ],
)
def test_a_placing_in_a_request_or_after_a_fetch(office, text, goals):
    result = office.ground(office_map(office), text, robot_cell=(10, 10))
    steps = result.steps or [result]
    assert len(steps) == len(goals) and all(map(lands, steps, goals)), (text, result.reason)


@pytest.mark.parametrize(
    'text',
    ['put the cup down', 'please put it down', 'drop it off', 'leave the sofa',
     'put the chair down', 'leave the fridge'],  # a landmark left or put down: still no place
)
def test_a_placing_that_says_no_place_declines(office, text):
    result = office.ground(office_map(office), text)
    assert result.goal is None and result.reason.endswith('says no place'), result.reason


@pytest.mark.parametrize(
    'text, landmark',
    [('place the box under the rock', 'rock'), ('put the cup on the piano', 'piano'),
     ('place the object under the rock', 'rock')],
)
def test_a_placing_to_a_landmark_not_in_the_table_names_the_landmark(office, text, landmark):
    """The thing placed is no landmark: the decline names the place's ("rock"), not "box"."""
    result = office.ground(office_map(office), text)
    assert result.goal is None and result.reason == f'unknown-landmark: {landmark}'


@pytest.mark.parametrize(
    'text, goal',
    [
        ('leave the sofa and go to the fridge', beside((3, 3))),
        ('put the chair down and go to the fridge', beside((3, 3))),  # not "2 chairs"
        ('put the cup down then go to the sofa', beside((8, 6))),  # "down" is no direction
        ('drop the box, then head to the desk', beside((5, 9))),
    ],
)
def test_a_placing_with_no_place_before_a_step_is_done_where_the_robot_is(office, text, goal):
    result = office.ground(office_map(office), text, robot_cell=(10, 10))
    assert result.intent == 'go' and lands(result, goal), (text, result.goal, result.reason)


@pytest.mark.parametrize(
    'horse, text, goal',
    [
        ((4, 7), 'left of the horse and right of the heart', (4, 5)),  # between them
        ((4, 7), 'go to the right of the heart and to the left of the horse', (4, 5)),
        ((4, 5), 'the cell left of the horse and right of the heart', (4, 4)),  # one from each
        ((6, 3), 'below the heart and above the horse', (5, 3)),
        ((6, 4), 'below the heart and above the horse', None),  # no one cell: halfway is not
        ((4, 6), 'left of the horse and right of the heart', None),  # an even gap
        ((4, 7), 'right of the horse and left of the heart', None),  # no cell is both
        ((4, 7), 'three left of the horse and one right of the heart', (4, 4)),  # counts: exact
        ((4, 7), 'one left of the horse and one right of the heart', None),  # no one cell
    ],
)
def test_a_cell_said_by_two_landmarks_sides(puddleworld, horse, text, goal):
    grid = np.zeros((10, 10), dtype=np.int64)
    grid[4, 3], grid[horse] = 5, 11  # heart, horse
    result = puddleworld.ground(grid, text)
    assert result.goal == goal, (text, result.reason)
    assert goal is not None or result.reason.startswith('ambiguous')


@pytest.mark.parametrize(
    'text, goal',
    [
        ('one below the rock and one over to the left', (8, 7)),
        ('go over to the left of the rock', (7, 7)),
        ('walk down to the rock', (7, 8)),  # "down to": the verb's, no side
        ('one above the rock and two down to the left', None),  # down and left: opposite sides
    ],
)
def test_a_side_word_before_to_is_read_one_way(puddleworld, text, goal):
    grid = np.zeros((10, 10), dtype=np.int64)
    grid[7, 8] = 8  # rock
    result = puddleworld.ground(grid, text)
    assert result.goal == goal, (text, result.reason)


@pytest.mark.parametrize(
    'text',
    ['the chair nearest to me', 'go to the chair near me', 'the chair closest to the robot',
     'the nearest chair to you'],
)
def test_a_landmark_nearest_the_robot_said_of_it(office, text):
    """The chair nearest the robot, at (10, 10): (9, 2), not (2, 8); without its cell, asked."""
    grid = office_map(office)
    assert lands(office.ground(grid, text, robot_cell=(10, 10)), beside((9, 2))), text
    assert office.ground(grid, text).reason.startswith('ambiguous: said of the robot'), text


def test_between_the_two_of_a_kind(office, puddleworld):
    """Say 'between the two chairs' of the map's two; one sofa, or three trees, are not two."""
    grid = office_map(office)
    assert office.ground(grid, 'go between the two chairs').goal == (5, 5)
    assert office.ground(grid, 'between the two sofas').reason.startswith('ambiguous: 1 sofa')
    grid = np.zeros((10, 10), dtype=np.int64)
    grid[2, 2] = grid[2, 6] = grid[7, 7] = 9  # three trees
    grid[2, 4] = 10  # a house between two of them
    assert puddleworld.ground(grid, 'reach house between two trees').goal == (2, 4)
    assert puddleworld.ground(grid, 'the cell between two trees').reason.startswith(
        'ambiguous: 3 trees'
    )


@pytest.mark.parametrize(
    'text, goal',
    [
        ('go to the left of the fridge, not the right', (3, 2)),  # the side said again
        ('left of the sofa, not the right side', (8, 5)),
        ('go to the fridge, not the right', None),  # which side, then? declined
        ('go to whichever chair is closer', beside((9, 2))),  # nearest the robot at (10, 10)
        ('the chair that is closest', beside((9, 2))),
    ],
)
def test_a_side_set_aside_and_the_closer_one(office, text, goal):
    result = office.ground(office_map(office), text, robot_cell=(10, 10))
    assert lands(result, goal), (text, result.reason)
