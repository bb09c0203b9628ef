# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
One checkpoint format, one writer, one reader; the grid and ShapeWorld loaders on top.

The reader refuses a checkpoint of the other family in one line, from Python and from the
command line, and every shipped checkpoint loads as it was written.
"""

import subprocess
import sys

import pytest
from spatial_grounding_ros.core.entities import PUDDLEWORLD
from spatial_grounding_ros.core.text import Vocabulary
from spatial_grounding_ros.models.checkpoints import (
    FORMAT,
    load_checkpoint,
    PACKAGED_DIR,
    read_checkpoint,
    save_checkpoint,
)
from spatial_grounding_ros.models.config import ModelConfig
from spatial_grounding_ros.models.registry import build_model
from spatial_grounding_ros.shapeworld import training as shapeworld
from spatial_grounding_ros.shapeworld.models import build_model as build_shapeworld
from spatial_grounding_ros.shapeworld.models import ShapeWorldConfig
import torch

SHIPPED = sorted(p.stem for p in PACKAGED_DIR.glob('*.pt'))
VOCAB = Vocabulary.build(['a red circle is above a square', 'go to the tree'])


@pytest.fixture
def written(tmp_path):
    """Write a small grid checkpoint and a small ShapeWorld one, each by its family's saver."""
    grid_cfg = ModelConfig(vocab_size=len(VOCAB))
    grid = save_checkpoint(
        tmp_path / 'grid.pt', 't-cnn', build_model('t-cnn', grid_cfg), grid_cfg, VOCAB,
        PUDDLEWORLD, task='pw',
    )
    sw_cfg = ShapeWorldConfig(vocab_size=len(VOCAB))
    sw = shapeworld.save(
        tmp_path / 'sw.pt', 't-vgg', build_shapeworld('t-vgg', sw_cfg), sw_cfg, VOCAB, epochs=1
    )
    return grid, sw


def test_both_savers_write_one_format(written):
    grid, sw = written
    for path, family in ((grid, 'grid'), (sw, 'shapeworld')):
        _, header, state = read_checkpoint(path, family)
        assert header['format'] == FORMAT and header['vocabulary'] == list(VOCAB.words)
        assert set(state) == set(torch.load(path, weights_only=True)['state_dict'])
    assert read_checkpoint(sw, 'shapeworld')[1]['task'] == 'shapeworld'
    assert 'entities' in read_checkpoint(grid, 'grid')[1]
    assert load_checkpoint(grid).name == 't-cnn'
    assert shapeworld.load(sw)[2]['epochs'] == 1


def test_the_reader_refuses_the_other_family(written):
    grid, sw = written
    with pytest.raises(ValueError, match='sw.pt: holds a ShapeWorld image classifier'):
        read_checkpoint(sw, 'grid')
    with pytest.raises(ValueError, match='grid.pt: holds a value-map model'):
        read_checkpoint(grid, 'shapeworld')
    with pytest.raises(ValueError, match='not a value-map model'):
        load_checkpoint(sw)
    with pytest.raises(ValueError, match='not a ShapeWorld image classifier'):
        shapeworld.load(grid)


def test_the_reader_refuses_what_is_no_checkpoint(tmp_path):
    (tmp_path / 'bad.pt').write_bytes(b'garbage')
    torch.save({'weights': {}}, tmp_path / 'bare.pt')
    torch.save({'header': {'format': 'other/9'}, 'state_dict': {}}, tmp_path / 'other.pt')
    for name, needle in (
        ('bad.pt', 'bad.pt: not a readable checkpoint'),
        ('bare.pt', 'bare.pt: not a spatial_grounding_ros checkpoint'),
        ('other.pt', "other.pt: checkpoint format 'other/9'"),
    ):
        for family in ('grid', 'shapeworld'):
            with pytest.raises(ValueError, match=needle):
                read_checkpoint(tmp_path / name, family)
    with pytest.raises(FileNotFoundError, match='nope.pt: checkpoint not found'):
        read_checkpoint(tmp_path / 'nope.pt', 'shapeworld')


@pytest.mark.parametrize('name', SHIPPED)
def test_every_shipped_checkpoint_loads_through_its_family(name):
    if name.startswith('shapeworld_'):
        model, _, header = shapeworld.load(name)
        with pytest.raises(ValueError, match='ShapeWorld image classifier'):
            load_checkpoint(name)
    else:
        loaded = load_checkpoint(name)
        model, header = loaded.model, loaded.header
        with pytest.raises(ValueError, match='value-map model'):
            shapeworld.load(name)
    assert name.endswith(header['model']) and not model.training


def assert_one_line_error(*argv, needle):
    r = subprocess.run(
        [sys.executable, '-m', 'spatial_grounding_ros.cli', *argv],
        capture_output=True, text=True, timeout=300,
    )
    assert r.returncode == 2, r.stderr
    [line] = r.stderr.strip().splitlines()
    assert line.startswith('spatial-grounding: error: ') and needle in line


def test_shapeworld_eval_refuses_a_grid_checkpoint_in_one_line():
    assert_one_line_error(
        'shapeworld-eval', '--checkpoint', 'pw_t-rnet-attn', needle='holds a value-map model'
    )


def test_eval_refuses_a_shapeworld_checkpoint_in_one_line(data_dir):
    assert_one_line_error(
        'eval', '--checkpoint', 'shapeworld_t-vgg', '--task', 'pw', '--data', str(data_dir),
        needle='holds a ShapeWorld image classifier',
    )
