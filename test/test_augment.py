# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""Mirror augmentation: mirrored examples are exactly correct examples."""

from collections import Counter

import numpy as np
import pytest
from spatial_grounding_ros.core import world
from spatial_grounding_ros.core.text import PAD, tokenize, UNK, Vocabulary
from spatial_grounding_ros.data import datasets, generator
from spatial_grounding_ros.data.augment import (
    absent_name_pools,
    filler_word_ids,
    insert_noise_words,
    mirror,
    MIRROR_IMAGES,
    mirror_instruction,
    SWAP_LEFT_RIGHT,
    SWAP_TABLES,
    SWAP_UP_DOWN,
    swap_words,
    with_mirrors,
)
from spatial_grounding_ros.data.noise import ARTICLES, VERBS
import torch


@pytest.mark.parametrize('axis', [1, 2])
def test_mirrored_value_maps_are_the_true_ones(axis):
    data = generator.generate(20, seed=3, mode='mixed')
    flipped = mirror(data, axis)
    np.testing.assert_allclose(
        world.value_iteration(flipped.rewards, flipped.terminal), flipped.values, atol=1e-4
    )
    np.testing.assert_array_equal(world.argmax_cells(flipped.values), flipped.goals)
    twice = mirror(flipped, axis)
    np.testing.assert_array_equal(twice.grids, data.grids)
    np.testing.assert_array_equal(twice.goals, data.goals)


def test_direction_words_swap_with_the_flip():
    assert (
        swap_words('Two cells left of the westernmost rock.', SWAP_LEFT_RIGHT)
        == 'two cells right of the easternmost rock'
    )
    assert (
        swap_words('reach the cell above the top-most tree', SWAP_UP_DOWN)
        == 'reach the cell below the bottom most tree'
    )
    assert (
        swap_words('one bellow the northern house', SWAP_UP_DOWN) == 'one above the southern house'
    )
    # words without a direction are untouched
    assert swap_words('reach the heart', SWAP_UP_DOWN) == 'reach the heart'


def test_a_mirror_image_swaps_words_one_for_one():
    """Each image's wording has as many tokens as the words (the grounder encodes each alone)."""
    for table in SWAP_TABLES.values():
        assert all(len(tokenize(a)) == len(tokenize(b)) == 1 for a, b in table.items())
    for text in ('Two cells left of the westernmost rock.', 'reach the top-most tree, then stop',
                 'go one north-east of the lower left house', 'the tree at the bottom right'):
        for axes in MIRROR_IMAGES:
            assert len(tokenize(mirror_instruction(text, axes))) == len(tokenize(text))


def test_with_mirrors_is_four_times_the_data():
    data = generator.generate(5, seed=1, mode='local')
    out = with_mirrors(data)
    assert len(out) == 20
    assert out.grids.shape == (20, *data.grids.shape[1:])
    with pytest.raises(ValueError, match='mirror axis'):
        mirror(data, 0)


@pytest.mark.parametrize('tasks,min_count', [(('pw-local', 'pw-global'), 1), (('isi',), 2)])
def test_every_direction_word_in_train_has_a_mirror(data_dir, tasks, min_count):
    """A direction word the tables miss would mislabel its mirrored examples."""
    counts = Counter(
        w
        for task in tasks
        for text in datasets.load_task(task, 'train', data_dir).instructions
        for w in tokenize(text)
    )
    words = {w for w, n in counts.items() if n >= min_count}
    # words that only contain a direction's letters; "ups" is ISI's UPS logo block
    horizontal = [
        w
        for w in words - {'lowest', 'least'}
        if any(r in w for r in ('left', 'right', 'east', 'west'))
    ]
    vertical = [
        w
        for w in words - {'highlighting', 'yellow', 'stop', 'stopping', 'ups', "ups's", 'overlap'}
        if any(
            r in w
            for r in (
                'above',
                'below',
                'bellow',
                'north',
                'south',
                'top',
                'bottom',
                'upper',
                'lower',
                'under',
                'beneath',
                'up',
                'down',
                'high',
                'low',
                'over',
            )
        )
    ]
    assert not [w for w in horizontal if w not in SWAP_LEFT_RIGHT]
    assert not [w for w in vertical if w not in SWAP_UP_DOWN]


def test_direction_words_that_are_not_directions_stay():
    """ISI blocks are picked up, lined up and put right next to one another: no flip moves that."""
    assert (
        swap_words(
            'Pick up block 3 and put it right next to the right side of block 4', SWAP_LEFT_RIGHT
        )
        == 'pick up block 3 and put it right next to the left side of block 4'
    )
    assert (
        swap_words('move it up until it is lined up with block 2', SWAP_UP_DOWN)
        == 'move it down until it is lined up with block 2'
    )
    assert (
        swap_words('put it right on top of block 5', SWAP_LEFT_RIGHT)
        == 'put it right on top of block 5'
    )
    # "right" before a direction is itself a direction ("one to the right below the tree")
    assert (
        swap_words('one to the right below the tree', SWAP_LEFT_RIGHT)
        == 'one to the left below the tree'
    )


def test_noise_words_keep_the_instruction_in_order_at_one_position():
    data = generator.generate(200, seed=5, mode='local')
    vocab = Vocabulary.build(data.instructions)
    fillers = filler_word_ids(vocab)
    assert {vocab.words[i] for i in fillers} == {*VERBS, *ARTICLES} & set(vocab.words)
    tokens = torch.from_numpy(vocab.encode_batch(data.instructions))
    noisy = insert_noise_words(tokens, fillers, 4, np.random.default_rng(0))
    again = insert_noise_words(tokens, fillers, 4, np.random.default_rng(0))
    assert torch.equal(noisy, again)  # seeded
    clean, unknown = 0, 0
    for before, after in zip(tokens.tolist(), noisy.tolist()):
        before, after = [t for t in before if t != PAD], [t for t in after if t != PAD]
        k = len(after) - len(before)
        assert 0 <= k <= 4
        clean += k == 0
        # the instruction's own words, in order, around one run of k inserted ones
        at = next((i for i, (a, b) in enumerate(zip(before, after)) if a != b), len(before))
        assert after[:at] + after[at + k:] == before
        inserted = after[at:at + k]
        # unknown words or fillers, never a kind's name
        assert set(inserted) <= {UNK, *fillers.tolist()}
        unknown += inserted.count(UNK)
    assert 60 < clean < 140  # about half stay clean
    assert unknown > 50  # about half the inserted words are <unk>


def test_absent_name_pools_by_hand():
    """The names noise_names may insert: kinds neither on the map nor named."""
    name_ids = np.array([10, 11, 12, -1, 14, 15])  # kind 3's name is not a word of the vocabulary
    grids = torch.tensor([[[0, 1], [2, 0]], [[0, 0], [0, 0]]])
    tokens = torch.tensor([[7, 15, 8], [14, 7, 0]])
    first, second = absent_name_pools(grids, tokens, name_ids)
    assert first.tolist() == [14]  # 0, 1, 2 on the map, 3 has no word, 5 named
    assert second.tolist() == [11, 12, 15]  # 0 on the map, 4 named


def test_noise_names_insert_only_names_of_absent_kinds():
    data = generator.generate(200, seed=5, mode='local')
    vocab = Vocabulary.build(data.instructions)
    fillers = filler_word_ids(vocab)
    name_ids = np.array([vocab.index.get(n, -1) for n in data.entities.names])
    grids = torch.from_numpy(data.grids)
    tokens = torch.from_numpy(vocab.encode_batch(data.instructions))
    pools = absent_name_pools(grids, tokens, name_ids)
    noisy = insert_noise_words(tokens, fillers, 6, np.random.default_rng(0), pools)
    kinds = {'unknown': 0, 'filler': 0, 'name': 0}
    for before, after, pool in zip(tokens.tolist(), noisy.tolist(), pools):
        before, after = [t for t in before if t != PAD], [t for t in after if t != PAD]
        k = len(after) - len(before)
        at = next((i for i, (a, b) in enumerate(zip(before, after)) if a != b), len(before))
        assert after[:at] + after[at + k:] == before
        for word in after[at:at + k]:
            if word == UNK:
                kinds['unknown'] += 1
            elif word in fillers:
                kinds['filler'] += 1
            else:
                assert word in pool.tolist()  # a name, and one of a kind the map lacks
                kinds['name'] += 1
    total = sum(kinds.values())
    assert all(n > total / 5 for n in kinds.values()), kinds  # about a third each


def test_noise_for_a_model_that_skips_unknown_words_is_fillers_and_names():
    """Without `unknown` no <unk> is inserted (it would be no noise); `share` sets how many."""
    data = generator.generate(200, seed=5, mode='local')
    vocab = Vocabulary.build(data.instructions)
    fillers = filler_word_ids(vocab)
    name_ids = np.array([vocab.index.get(n, -1) for n in data.entities.names])
    tokens = torch.from_numpy(vocab.encode_batch(data.instructions))
    pools = absent_name_pools(torch.from_numpy(data.grids), tokens, name_ids)
    for names in (None, pools):
        noisy = insert_noise_words(
            tokens, fillers, 6, np.random.default_rng(0), names, unknown=False, share=0.9
        )
        added = (noisy != PAD).sum(1) - (tokens != PAD).sum(1)
        # <unk> only where a map holds every named kind: no name left to insert
        lacking = [i for i, pool in enumerate(names or []) if not len(pool)]
        assert set(torch.nonzero(noisy == UNK)[:, 0].tolist()) <= set(lacking)
        assert 160 < (added > 0).sum() < 200  # about 9 in 10 get noise
    inserted = noisy[(noisy != PAD) & ~torch.isin(noisy, tokens)]
    assert torch.isin(inserted, torch.from_numpy(fillers)).float().mean() < 0.75  # names too
