# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""People's wordings become the model's words, and words it never saw cannot move the goal."""

import numpy as np
import pytest
from spatial_grounding_ros.core.text import tokenize
from spatial_grounding_ros.data.generator import generate
from spatial_grounding_ros.data.paraphrase import paraphrase, paraphrased
from spatial_grounding_ros.grounder import Grounder
from spatial_grounding_ros.language.wording import (
    canonical,
    cell_for_fixed_target,
    count_first,
    drop_unknown,
    side_of_it,
    tidy,
    unpossessed,
)


@pytest.mark.parametrize(
    'said, meant',
    [
        ('please drive two squares south of the star', 'reach two below the star'),
        ('the robot should stop on the spot 3 steps east of the rock',
         'reach the cell three to the right of the rock'),
        ('navigate to the tree nearest to the heart thanks',
         'reach the tree closest to the heart'),
        ('go to the leftmost house', 'reach the westernmost house'),
        # the human PuddleWorld annotators' own extremes
        ('go to the left most tree', 'reach the westernmost tree'),
        ('the bottom most house', 'the southernmost house'),
        ('move to the upper most rock', 'reach the northernmost rock'),
        ('go to the most right horse', 'reach the easternmost horse'),
        ('move to the place in between the star and the circle',
         'reach the cell between the star and the circle'),
        ('go to the second square below the sink', 'reach the cell two below the sink'),
        ('drive to the place upward from the sink', 'reach the cell above the sink'),
        ('move 2 squares downward from the bin', 'reach two below the bin'),
        ('go to the area right above the lamp', 'reach the cell above the lamp'),
        ('head to the chair nearest the door', 'reach the chair closest to the door'),
        ('stop right next to the fridge', 'reach closest to the fridge'),
        ('reach cell two below star', 'reach cell two below star'),  # the model's own
        ('reach cell to left of star', 'reach cell to left of star'),
    ],
)
def test_wordings_become_the_models_words(said, meant):
    assert ' '.join(canonical(tokenize(said))) == meant


def test_a_landmark_name_is_never_reworded():
    words = tokenize('go two cells under the spot')  # a landmark called "spot"
    assert canonical(words, keep=[5]) == ['reach', 'two', 'below', 'the', 'spot']
    assert canonical(words) == ['reach', 'two', 'below', 'the', 'cell']


def test_unknown_words_are_left_out_unless_nothing_is_left():
    assert drop_unknown(['reach', 'zorp', 'star'], {'reach', 'star'}) == ['reach', 'star']
    assert drop_unknown(['zorp'], {'reach'}) == ['zorp']


def test_paraphrases_keep_names_and_vary():
    rng = np.random.default_rng(0)
    texts = {paraphrase('reach cell two below star', rng, {'star'}) for _ in range(30)}
    assert len(texts) > 10 and all(t.split()[-1] in ('star', 'please', 'thanks', 'now')
                                   or 'star' in t.split() for t in texts)


def test_a_share_of_generated_instructions_is_paraphrased_into_the_same_request():
    """The training augmentation: worlds kept, a share reworded, each read back as it was."""
    data = generate(300, seed=2, mode='training')
    reworded = paraphrased(data, 0.5, seed=2)
    assert np.array_equal(reworded.grids, data.grids) and reworded.goals is data.goals
    changed = [(a, b) for a, b in zip(data.instructions, reworded.instructions) if a != b]
    assert 0.3 < len(changed) / len(data) < 0.55  # some draws keep every phrase as it was
    for before, after in changed:
        read = canonical(tokenize(after))
        # the grammar reads the request back: the same words, but the filler and the units
        assert [w for w in read if w not in ('cell', 'the')] == [
            w for w in tokenize(before) if w not in ('cell', 'the')
        ], (before, after)
    assert paraphrased(data, 0.0, seed=2) is data


@pytest.fixture(scope='module')
def grounder():
    return Grounder.from_checkpoint()


def test_unknown_and_filler_words_do_not_move_the_goal(grounder):
    grid = np.zeros((10, 10), dtype=np.int64)
    grid[3, 4], grid[6, 7] = 2, 8  # a star, a rock
    plain = grounder.ground(grid, 'reach cell two below the star')
    for noisy in (
        'zorp reach cell two below the star quux',
        'please, robot, go two squares south of the star now',
        'blorf the robot should drive 2 spaces beneath the star thanks',
    ):
        g = grounder.ground(grid, noisy)
        assert (g.goal, g.reason) == (plain.goal, None), g.model_instruction
    assert plain.goal == (5, 4)


@pytest.mark.parametrize(
    'text, said',
    [
        ('reach rock one below star and two to the left of circle',
         'reach cell one below star and two to the left of circle'),
        ('reach the tree two above heart and one to the right of spade',
         'reach the cell two above heart and one to the right of spade'),
        ('reach rock closest to star', None),  # the rock is what picks the cell
        ('reach rock between star and circle', None),  # no offsets
        ('reach cell one below star and two to the left of circle', None),
    ],
)  # fmt: skip
def test_a_target_that_two_offsets_fix_is_said_as_a_cell(text, said):
    words = tokenize(text)
    names = [i for i, w in enumerate(words) if w in {'rock', 'tree', 'star', 'circle', 'heart',
                                                     'spade'}]
    assert ' '.join(cell_for_fixed_target(words, names)) == (said or text)


@pytest.mark.parametrize(
    'text, said',
    [
        ('reach the go a the northernmost locate rock', 'reach the northernmost rock'),
        ('go to the rock', 'go to the rock'),  # the opening verb stays
        ('reach cell go two below star', 'reach cell two below star'),
        ('move the a an star', 'move an star'),  # a run of articles says one
    ],
)
def test_tidy_leaves_out_verbs_past_the_opening_and_repeated_articles(text, said):
    assert ' '.join(tidy(text.split())) == said


def test_a_cell_word_is_the_cell_only_where_a_relation_follows():
    assert canonical(tokenize('go to the square two below the star'))[:3] == [
        'reach', 'the', 'cell'
    ]
    # inserted before an extreme it says no cell: left for the vocabulary to keep or drop
    assert canonical(tokenize('reach the tile westernmost rock')) == [
        'reach', 'the', 'tile', 'westernmost', 'rock'
    ]


def test_words_the_wording_layer_reads_are_not_reported_unknown(grounder):
    grid = np.zeros((10, 10), dtype=np.int64)
    grid[3, 4] = 2  # a star
    g = grounder.ground(grid, 'please go two squares south of the star zorp')
    assert g.unknown_words == ['zorp']


def test_a_side_said_as_the_landmarks_own_is_the_side_of_it():
    assert unpossessed("go 2 cells to the fridge's left") == 'go 2 cells to the left of the fridge'
    assert unpossessed("the coffee machine's right hand side") == (
        'the right of the coffee machine'
    )
    assert unpossessed("the plant's southern side") == 'the south of the plant'
    assert unpossessed("the fridge's door") == "the fridge's door"  # no side: as it was


def test_a_count_said_after_its_landmark_is_said_before_it():
    assert count_first('go directly north of the trash can by two cells') == (
        'go two cells directly north of the trash can'
    )
    assert count_first('stop left of the door by 1.5 m') == 'stop 1.5 m left of the door'
    assert count_first('go above the forklift, two cells') == 'go two cells above the forklift'
    assert count_first('go by the door') == 'go by the door'  # no count: as it was
    assert count_first('go to the left of the desk') == 'go to the left of the desk'
    # two-word sides, a side said "from", "diagonally"
    assert count_first('go diagonally up-left from the fridge by one') == (
        'go one diagonally up-left from the fridge'
    )
    assert count_first('go down and to the left of the sofa by 2 cells') == (
        'go 2 cells down and to the left of the sofa'
    )
    assert count_first('go northeast of the sofa by two') == 'go two northeast of the sofa'


def test_a_count_after_the_landmark_moves_the_goal_by_it(grounder):
    grid = np.zeros((10, 10), dtype=np.int64)
    grid[6, 4] = 2  # a star
    assert grounder.ground(grid, 'go north of the star by three squares').goal == (3, 4)
    assert grounder.ground(grid, 'go north of the star by one square').goal == (5, 4)
    assert grounder.ground(grid, 'go diagonally up-left from the star by one').goal == (5, 3)


def test_a_second_description_after_a_comma_is_no_count_of_the_first(grounder):
    assert count_first('two right of the star, two left of the heart') == (
        'two right of the star, two left of the heart'
    )
    grid = np.zeros((10, 10), dtype=np.int64)
    grid[6, 4], grid[6, 8] = 2, 5  # a star, a heart
    assert grounder.ground(grid, 'two right of the star, two left of the heart').goal == (6, 6)


def test_a_side_of_its_landmark_is_said_of_the_landmark():
    words = 'reach the star and one to its left'.split()
    assert side_of_it(words, [2]) == 'reach one to the left of the star'.split()
    words = 'reach closest to the star on its bottom side'.split()
    assert side_of_it(words, [4]) == 'reach below the star'.split()
    words = 'the blue star one to the left'.split()
    assert side_of_it(words, [2]) == 'one to the left of the blue star'.split()
    assert side_of_it('the star two down'.split(), [1]) == 'two below the star'.split()
    # which star, or more than a side of it: the words stay
    for said in (
        'reach the star on the right',
        'reach the cell below the star then two to the left',
    ):
        assert side_of_it(said.split(), [said.split().index('star')]) == said.split()
    # two landmarks: "its" could be either, the words stay
    words = 'reach the star and the circle to its left'.split()
    assert side_of_it(words, [2, 5]) == words


def test_a_side_of_it_moves_the_goal_to_that_side(grounder):
    grid = np.zeros((10, 10), dtype=np.int64)
    grid[6, 4] = 2  # a star
    assert grounder.ground(grid, 'go to the star and stop two cells to its left').goal == (6, 2)
    assert grounder.ground(grid, 'find the star and wait on its north side').goal == (5, 4)
