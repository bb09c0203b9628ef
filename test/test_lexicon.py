# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""Entity tables with aliases, finding their landmarks in words, and grounding them by role."""

import numpy as np
import pytest
from spatial_grounding_ros.core.entities import (
    EntityTable,
    PUDDLEWORLD,
    PUDDLEWORLD_NONUNIQUE,
    PUDDLEWORLD_UNIQUE,
)
from spatial_grounding_ros.grounder import Grounder
from spatial_grounding_ros.language.lexicon import (
    COMMON_WORDS,
    Lexicon,
    singular,
    Translation,
    within_one_edit,
)
import yaml

KITCHEN = {
    'domain': 'kitchen',
    'names': ['floor', 'wall', 'fridge', 'sink', 'coffee_machine', 'chair', 'box'],
    'obstacles': [1],
    'embed_dim': 7,
    'aliases': {'fridge': ['refrigerator'], 'coffee_machine': 'espresso maker', 'box': []},
}


def kitchen() -> EntityTable:
    return EntityTable.from_dict(KITCHEN)


def test_a_table_reads_aliases_and_writes_them_back(tmp_path):
    path = tmp_path / 'kitchen.yaml'
    path.write_text(yaml.safe_dump(KITCHEN))
    table = EntityTable.from_yaml(path)
    assert table.aliases_of(2) == ('refrigerator',)
    assert table.aliases_of(4) == ('espresso maker',)
    assert table.aliases_of(6) == ()
    assert EntityTable.from_dict(table.to_dict()) == table
    # a table without aliases is the table it always was (checkpoint headers compare equal)
    assert 'aliases' not in PUDDLEWORLD.to_dict()
    assert EntityTable.from_dict(PUDDLEWORLD.to_dict()) == PUDDLEWORLD


def test_a_users_table_needs_only_names_and_obstacles(tmp_path):
    path = tmp_path / 'galley.yaml'
    path.write_text(yaml.safe_dump({'names': ['deck', 'bulkhead', 'stove'], 'obstacles': [1]}))
    table = EntityTable.from_yaml(path)
    assert (table.domain, table.embed_dim) == ('galley', PUDDLEWORLD.embed_dim)
    with pytest.raises(ValueError, match='it needs names and obstacles'):
        EntityTable.from_dict({'names': ['deck']})


@pytest.mark.parametrize(
    'change, message',
    [
        ({'aliases': {'oven': ['stove']}}, "aliases name \\['oven'\\]"),
        ({'aliases': {'fridge': ['']}}, 'must be non-empty strings'),
        ({'aliases': ['fridge']}, 'aliases must map a name'),
        ({'obstacles': [9]}, 'obstacles \\[9\\] are not indices'),
    ],
)
def test_a_malformed_table_says_what_is_wrong(change, message):
    with pytest.raises(ValueError, match=message):
        EntityTable.from_dict({**KITCHEN, **change})


def test_free_ground_is_never_a_landmark():
    table = EntityTable.from_dict({'names': ['tiles', 'wall', 'oven'], 'obstacles': [1]})
    lexicon = Lexicon(table, COMMON_WORDS)
    # a floor of tiles: "tile" is the cell, as in any instruction
    assert [m.kind for m in lexicon.mentions('go to the tile above the oven')] == [2]
    grid = np.zeros((8, 8), dtype=np.int64)
    grid[5, 4] = 2
    g = Grounder.from_checkpoint(entities=table)
    assert g.ground(grid, 'move to the tile 3 cells above the oven').goal == (2, 4)


def test_plurals_and_edits():
    assert [singular(w) for w in ('fridges', 'boxes', 'libraries', 'glass', 'bus')] == [
        'fridge',
        'box',
        'library',
        'glass',
        'bus',
    ]
    assert within_one_edit('fridge', 'fidge')  # a letter dropped
    assert within_one_edit('fridge', 'frdige')  # two swapped
    assert within_one_edit('fridge', 'fridgge')  # one added
    assert within_one_edit('fridge', 'fridqe')  # one changed
    assert not within_one_edit('fridge', 'fdirge')


def test_mentions_find_names_aliases_plurals_and_typos_in_order():
    lexicon = Lexicon(kitchen(), COMMON_WORDS)
    found = lexicon.mentions('Go two cells below the Espresso Maker, then to the Refrigerators!')
    assert [(m.kind, m.words) for m in found] == [
        (4, ('espresso', 'maker')),
        (2, ('refrigerators',)),
    ]
    assert lexicon.mentioned_kinds('the chiar closest to the frdige and the fridge') == [5, 2]
    assert lexicon.mentioned_kinds('the coffee machine') == [4]  # the name's own words


def test_relation_words_are_never_read_as_typos_of_names():
    table = EntityTable('t', ('grass', 'water', 'tree', 'star', 'door'), (1,), 7)
    lexicon = Lexicon(table, COMMON_WORDS)
    assert lexicon.mentioned_kinds('reach cell three below the start') == []
    assert lexicon.mentioned_kinds('reach cell three below the tre') == [2]


def translation(table: EntityTable) -> Translation:
    return Translation(table, PUDDLEWORLD, PUDDLEWORLD_UNIQUE, PUDDLEWORLD_NONUNIQUE)


def test_a_table_the_model_never_saw_becomes_its_kinds_by_role():
    table = kitchen()
    grid = np.zeros((6, 6), dtype=np.int64)
    grid[0, :] = 1  # a wall
    grid[2, 2] = grid[4, 4] = 5  # two chairs
    grid[3, 1] = 2  # a fridge
    grid[5, 0] = 6  # a box nobody names
    t = translation(table)(grid, 'go to the chair closest to the refrigerator please')
    chair, fridge = t.kinds[5], t.kinds[2]
    assert PUDDLEWORLD.names[chair] in PUDDLEWORLD_NONUNIQUE  # held twice, and the target
    assert PUDDLEWORLD.names[fridge] in PUDDLEWORLD_UNIQUE
    assert t.instruction == (
        f'go to the {PUDDLEWORLD.names[chair]} closest to the {PUDDLEWORLD.names[fridge]} please'
    )
    want = np.zeros_like(grid)
    want[0, :] = 1  # the table's obstacle is the model's
    want[2, 2] = want[4, 4] = chair
    want[3, 1] = fridge  # and the box is free ground
    np.testing.assert_array_equal(t.grid, want)


def test_an_extreme_or_a_following_relation_makes_a_single_landmark_a_many_kind():
    grid = np.zeros((5, 5), dtype=np.int64)
    grid[1, 1], grid[3, 3] = 5, 2
    for text in ('reach the westernmost chair', 'reach the chair two below the fridge'):
        t = translation(kitchen())(grid, text)
        assert PUDDLEWORLD.names[t.kinds[5]] in PUDDLEWORLD_NONUNIQUE, text
    t = translation(kitchen())(grid, 'reach the cell two below the chair')
    assert PUDDLEWORLD.names[t.kinds[5]] in PUDDLEWORLD_UNIQUE


def test_names_the_model_knows_keep_their_kind():
    grid = np.arange(12).reshape(3, 4)
    t = translation(PUDDLEWORLD)(grid, 'reach cell two below the rokc near the tree')
    assert t.instruction == 'reach cell two below the rock near the tree'
    assert t.kinds == {8: 8, 9: 9}
    assert set(np.unique(t.grid)) == {0, 1, 8, 9}  # the unnamed landmarks are free ground


def test_a_three_letter_name_takes_a_changed_letter_but_not_a_common_word():
    table = EntityTable('t', ('floor', 'wall', 'bin', 'cup'), (1,), 7)
    lexicon = Lexicon(table, COMMON_WORDS)
    assert lexicon.mentioned_kinds('go to the bun then the cip') == [2, 3]
    assert lexicon.mentioned_kinds('can you go one up') == []  # "can" and "one" are words


def test_a_table_without_obstacles_still_renames_the_worlds():
    from spatial_grounding_ros.data.generator import sample
    from spatial_grounding_ros.data.renaming import rename

    table = EntityTable('open', ('floor', 'desk', 'chair', 'lamp', 'sofa', 'door', 'plant',
                                 'shelf', 'sink', 'oven', 'tv'), (), 7)
    grid, text, _ = sample(np.random.default_rng(0), 'two-step', 10)
    out, said = rename(grid, text, table, np.random.default_rng(1))
    assert out.max() < len(table) and (out[grid == 1] == 0).all() and said != text


def test_a_distance_reference_takes_roles_even_for_the_models_own_names():
    grid = np.zeros((6, 6), dtype=np.int64)
    grid[1, 1] = grid[4, 4] = PUDDLEWORLD.index('horse')
    grid[2, 3] = PUDDLEWORLD.index('heart')
    t = translation(PUDDLEWORLD)(grid, 'reach horse closest to heart')
    assert t.instruction == 'reach rock closest to star'  # the first roles of each pool
    t = translation(PUDDLEWORLD)(grid, 'reach the westernmost horse')
    assert t.instruction == 'reach the westernmost horse'  # by name: its identity kept


def test_names_of_landmarks_not_on_the_map_are_left_out_of_what_the_model_reads():
    grid = np.zeros((5, 5), dtype=np.int64)
    grid[2, 2] = PUDDLEWORLD.index('star')
    t = translation(PUDDLEWORLD)(grid, 'reach cell heart two below the star tree')
    assert t.instruction == 'reach cell two below the star'
    assert [m.kind for m in t.mentions] == [5, 2, 9]  # still mentioned: the checks decline


def test_kinds_by_name_always_or_role_always_for_the_ablation():
    grid = np.zeros((6, 6), dtype=np.int64)
    grid[1, 1] = grid[4, 4] = PUDDLEWORLD.index('horse')
    grid[2, 3] = PUDDLEWORLD.index('heart')
    by = {
        kinds_by: Translation(
            PUDDLEWORLD, PUDDLEWORLD, PUDDLEWORLD_UNIQUE, PUDDLEWORLD_NONUNIQUE, kinds_by
        )
        for kinds_by in ('name', 'name-always', 'role')
    }
    assert by['name-always'](grid, 'reach horse closest to heart').instruction == (
        'reach horse closest to heart'
    )
    assert by['role'](grid, 'reach the westernmost horse').instruction == (
        'reach the westernmost rock'
    )
    with pytest.raises(ValueError, match='kinds_by'):
        Translation(PUDDLEWORLD, PUDDLEWORLD, PUDDLEWORLD_UNIQUE, PUDDLEWORLD_NONUNIQUE, 'x')
