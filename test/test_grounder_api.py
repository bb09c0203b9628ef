# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The Python API refuses input it cannot ground, saying what is wrong.

A grid is a 2-D array of entity indices: anything that is not whole numbers inside the entity
table is a ValueError, never a grounding of something else (int64 would truncate 0.5 to grass).
"""

import numpy as np
import pytest
from spatial_grounding_ros.core.entities import PUDDLEWORLD
from spatial_grounding_ros.grounder import Grounder

TEXT = 'reach cell two below star'


@pytest.fixture(scope='module')
def grounder():
    return Grounder.from_checkpoint()


def star_map() -> np.ndarray:
    grid = np.zeros((10, 10), dtype=np.int64)
    grid[3, 4] = PUDDLEWORLD.index('star')
    return grid


@pytest.mark.parametrize(
    'grid, message',
    [
        (np.full((10, 10), 0.5), 'integer entity indices, got float64 values such as 0.5'),
        (star_map() + 0.25, 'got float64 values such as 0.25'),
        (np.where(star_map() > 0, np.nan, 0.0), 'got float64 values such as nan'),
        (np.full((4, 4), np.inf, dtype=np.float32), 'got float32 values such as inf'),
        (np.zeros((4, 4), dtype=bool), 'got bool values such as False'),
        (np.full((4, 4), '2'), 'integer entity indices, got <U1'),
        (np.full((3, 3), 12), r'entity values \[12\] outside the puddleworld table'),
        (np.zeros((0, 3), dtype=np.int64), 'non-empty 2-D array'),
        (np.zeros(5, dtype=np.int64), 'non-empty 2-D array'),
    ],
)
def test_a_grid_that_is_not_entity_indices_is_refused(grounder, grid, message):
    with pytest.raises(ValueError, match=message):
        grounder.ground(grid, TEXT)


def test_whole_numbers_in_any_dtype_ground_as_the_integers(grounder):
    expected = grounder.ground(star_map(), TEXT)
    assert expected.goal == (5, 4)
    for dtype in (np.float32, np.float64, np.int8, np.uint8, np.int32):
        got = grounder.ground(star_map().astype(dtype), TEXT)
        assert got.goal == expected.goal, dtype
        np.testing.assert_array_equal(got.values, expected.values)


@pytest.mark.parametrize(
    'text, message', [('', 'no words'), ('   ', 'no words'), ('zzz qqq', 'vocabulary')]
)
def test_an_instruction_without_known_words_is_refused(grounder, text, message):
    with pytest.raises(ValueError, match=message):
        grounder.ground(star_map(), text)
