# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Where the network is unsure, the Grounder's value map is the mean over the map's mirror images.

On maps up to a size (mirror_average_cells), when the map alone leaves the best cell's
calibrated probability under mirror_average_below.
"""

import numpy as np
import pytest
from spatial_grounding_ros.core.entities import PUDDLEWORLD
from spatial_grounding_ros.data.augment import mirror_instruction as mirrored
from spatial_grounding_ros.grounder import Grounder
import torch

E = PUDDLEWORLD.index


@pytest.fixture(scope='module')
def loaded():
    return Grounder.from_checkpoint().loaded


def model_map(loaded, grid, text):
    """Return the model's own value map of one map and one instruction, as `eval` computes it."""
    tokens = torch.as_tensor(loaded.vocab.encode_batch([text]))
    with torch.no_grad():
        return loaded.model(torch.as_tensor(grid)[None], tokens)[0].numpy()


def test_mirrored_instructions_swap_their_direction_words():
    text = 'reach cell two to the left of the westernmost rock and one above it'
    assert mirrored(text, (1,)) == (
        'reach cell two to the right of the easternmost rock and one above it'
    )
    assert mirrored(text, (0,)) == (
        'reach cell two to the left of the westernmost rock and one below it'
    )
    assert mirrored(mirrored(text, (1, 0)), (1, 0)) == text


def test_the_value_map_is_the_mean_over_the_mirror_images(loaded):
    grid = np.zeros((9, 11), dtype=np.int64)
    # (with the rock at (6, 8), one row above the other, the default of f315ee9 said (6, 9) at
    # confidence 0.31, today's (6, 10) at 0.48: a close call, not this test's point)
    grid[2, 3], grid[3, 8], grid[4, 1], grid[7, 2] = E('star'), E('rock'), E('tree'), E('rock')
    # (a count past one step from an extreme is composed, a shift of the network's map:
    # places.learned_offset; this one the network reads whole)
    text = 'reach the cell to the right of the northernmost rock'
    got = Grounder(loaded, mirror_average_below=1).ground(grid, text)  # every map
    single = Grounder(loaded, mirror_average_cells=0)
    want = np.mean(
        [
            np.flip(single.ground(np.flip(grid, axes).copy(), mirrored(text, axes)).values, axes)
            for axes in ((), (1,), (0,), (1, 0))
        ],
        0,
    )
    np.testing.assert_allclose(got.values, want, atol=1e-5)
    assert got.goal == (3, 9)  # right of the northernmost rock, (3, 8)
    one = single.ground(grid, text)
    assert not np.allclose(got.values, one.values)  # the images do add something
    # the single grounding is the model's own map of the grid the translation hands it
    model_grid = single.translation(grid, one.model_instruction).grid
    np.testing.assert_allclose(
        one.values, model_map(loaded, model_grid, one.model_instruction), atol=1e-5
    )


def test_maps_over_the_limit_are_grounded_once(loaded):
    grid = np.zeros((12, 12), dtype=np.int64)
    grid[5, 5] = E('star')
    text = 'reach cell two below star'
    limited = Grounder(loaded, mirror_average_cells=12 * 12 - 1, mirror_average_below=1)
    limited = limited.ground(grid, text)
    once = Grounder(loaded, mirror_average_cells=0).ground(grid, text)
    np.testing.assert_array_equal(limited.values, once.values)
    assert limited.goal == once.goal == (7, 5)


def test_only_an_unsure_map_is_averaged(loaded):
    """A sure grounding keeps the map's own value map; an unsure one takes the images' mean."""
    grid = np.zeros((9, 11), dtype=np.int64)
    grid[2, 3], grid[3, 8], grid[4, 1], grid[7, 2] = E('star'), E('rock'), E('tree'), E('rock')
    text = 'reach the cell to the right of the northernmost rock'
    single = Grounder(loaded, mirror_average_cells=0).ground(grid, text)
    always = Grounder(loaded, mirror_average_below=1).ground(grid, text)
    sure = single.confidence
    # under the map's own certainty nothing is averaged; above it, the images are
    below = Grounder(loaded, mirror_average_below=sure * 0.99).ground(grid, text)
    above = Grounder(loaded, mirror_average_below=min(1.0, sure * 1.01)).ground(grid, text)
    np.testing.assert_array_equal(below.values, single.values)
    np.testing.assert_allclose(above.values, always.values, atol=1e-6)
    with pytest.raises(ValueError, match='mirror_average_below'):
        Grounder(loaded, mirror_average_below=1.5)


def test_the_mirror_study_scores_each_setting(tmp_path):
    """`mirror-study`: never averages nothing, every map averages every map the network grounds."""
    from spatial_grounding_ros.studies.mirror import markdown, run_mirror_study

    result = run_mirror_study(data_dir=tmp_path, sizes=(10,), n=1, progress=False, natural=False)
    never, unsure, every = result['settings'].values()
    assert never['suite']['10']['mirrored'] == 0
    assert every['suite']['10']['mirrored'] >= unsure['suite']['10']['mirrored']
    assert every['suite']['10']['mirrored'] > 0.8  # all but the picks made on the map alone
    assert every['human'] == {}  # no data here: the human splits are left out
    table = markdown(result)
    assert table.startswith('| | never | below 0.95 (the default) | every map |')
