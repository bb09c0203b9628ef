# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Data sets.

The paper's split counts, ISI conversion, vocabulary, the world pickles' instructions.
"""

import gzip
import json

import numpy as np
import pytest
from spatial_grounding_ros.core import world
from spatial_grounding_ros.core.text import tokenize, UNK, Vocabulary
from spatial_grounding_ros.data import datasets


@pytest.mark.parametrize(
    'task,split,count',
    [
        ('pw-local', 'train', 1566),
        ('pw-local', 'test', 399),
        ('pw-global', 'train', 1071),
        ('pw-global', 'test', 272),
    ],
)
def test_puddleworld_split_counts(data_dir, task, split, count):
    data = datasets.load_task(task, split, data_dir)
    assert len(data) == count
    assert data.grids.shape == (count, 10, 10)
    # each value map is the true one of its goal
    np.testing.assert_array_equal(world.argmax_cells(data.values), data.goals)


def test_train_and_test_worlds_are_disjoint(data_dir):
    train = set(datasets.load_task('pw-local', 'train', data_dir).worlds)
    test = set(datasets.load_task('pw-local', 'test', data_dir).worlds)
    assert train and test and not train & test


@pytest.mark.parametrize('split,count', [('train', 11871), ('test', 3177)])
def test_isi_counts_and_grid(data_dir, split, count):
    """
    Counts, grid, and every value map.

    The reward map is the ISI conversion (+3 terminal at the goal, -1 on every block but the moved
    one, which leaves its cell), and the value map is what test/reference.py's value iteration
    makes of it, cell for cell.
    """
    import reference

    data = datasets.load_isi(data_dir, split)
    assert len(data) == count
    assert data.grids.shape[1:] == (13, 13)
    assert data.grids.max() <= 40 and len(data.entities) == 41
    # the goal is the true map's best cell
    np.testing.assert_array_equal(world.argmax_cells(data.values), data.goals)
    # one map per board step (its instructions share it)
    _, first = np.unique(data.worlds, return_index=True)
    grids, rewards, terminal, values, goals = (
        x[first] for x in (data.grids, data.rewards, data.terminal, data.values, data.goals)
    )
    n = np.arange(len(first))
    assert (terminal.sum(axis=(1, 2)) == 1).all() and terminal[n, goals[:, 0], goals[:, 1]].all()
    assert (rewards[terminal] == 3).all()
    obstacles = rewards == -1
    blocks = grids > 0
    assert set(np.unique(rewards[~terminal])) <= {0.0, -1.0}
    assert not (obstacles & ~blocks).any()  # only blocks are obstacles
    assert ((blocks & ~obstacles).sum(axis=(1, 2)) == 1).all()  # all but the moved one
    np.testing.assert_allclose(values, reference.value_iteration(rewards, terminal), atol=1e-5)


def test_isi_dev_split_loads_the_same_way(data_dir, tmp_path):
    (tmp_path / 'isi').mkdir()
    with gzip.open(data_dir / 'isi' / 'testset.json.gz', 'rt') as src:
        first = src.readline()
    with gzip.open(tmp_path / 'isi' / 'devset.json.gz', 'wt') as dst:
        dst.write(first)
    dev = datasets.load_task('isi', 'dev', tmp_path)
    seq = json.loads(first)
    assert len(dev) == sum(len(n['notes']) for n in seq['notes'] if n['type'] == 'A0')


def test_isi_validation_holds_out_whole_sequences(data_dir):
    """Steps of one ISI sequence share all but one block: validation must not see any of them."""
    train, val = datasets.split_by_world(datasets.load_isi(data_dir, 'train'), 0.1, seed=0)
    assert len(train) + len(val) == 11871 and len(val) > 500
    train_sequences = {w.rsplit('/', 1)[0] for w in train.worlds}
    assert len(train_sequences) == 63  # of ISI train's 70
    assert not train_sequences & {w.rsplit('/', 1)[0] for w in val.worlds}


def test_isi_cell_conversion():
    assert datasets.isi_cell(-1.0) == 0
    assert datasets.isi_cell(1.0) == 12
    assert datasets.isi_cell(0.0) == 6


def test_missing_and_corrupt_files_name_the_file(tmp_path):
    with pytest.raises(FileNotFoundError, match='local.p'):
        datasets.load_task('pw-local', 'train', tmp_path)
    (tmp_path / 'puddleworld').mkdir()
    (tmp_path / 'puddleworld' / 'local.p').write_bytes(b'not a pickle')
    with pytest.raises(ValueError, match='local.p: corrupt'):
        datasets.load_task('pw-local', 'train', tmp_path)
    (tmp_path / 'isi').mkdir()
    (tmp_path / 'isi' / 'trainset.json.gz').write_bytes(b'\x1f\x8b broken')
    with pytest.raises(ValueError, match='trainset.json.gz'):
        datasets.load_task('isi', 'train', tmp_path)
    with pytest.raises(ValueError, match='unknown task'):
        datasets.load_task('pw-nowhere', 'train', tmp_path)


def test_vocabulary_reserves_pad_and_unknown():
    vocab = Vocabulary.build(['reach the rock', 'go to the tree.'])
    assert vocab.words[:2] == ['<pad>', '<unk>']
    assert tokenize('Reach the ROCK.') == ['reach', 'the', 'rock']
    ids = vocab.encode_batch(['reach the zebra', 'tree'])
    assert ids.shape == (2, 3)
    assert ids[0, 2] == UNK and ids[1, 1] == 0


@pytest.mark.parametrize('task,floor', [('pw-local', 0.675), ('pw-global', 0.750), ('isi', 0.002)])
def test_a_final_relu_would_floor_the_mse(data_dir, task, floor):
    """
    Why the output layer has no final ReLU.

    Clipping the negative true values to 0 alone costs more than the paper's whole PW MSE (0.22
    local, 0.40 global).
    """
    values = datasets.load_task(task, 'test', data_dir).values.astype(np.float64)
    assert np.mean(np.minimum(values, 0) ** 2) == pytest.approx(floor, abs=5e-4)
