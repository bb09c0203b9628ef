"""Mirror augmentation: mirrored examples are exactly correct examples."""
import numpy as np
import pytest

from spatial_grounding_ros import datasets, generator, world
from spatial_grounding_ros.augment import (SWAP_LEFT_RIGHT, SWAP_UP_DOWN, mirror, swap_words,
                                           with_mirrors)
from spatial_grounding_ros.text import tokenize


@pytest.mark.parametrize("axis", [1, 2])
def test_mirrored_value_maps_are_the_true_ones(axis):
    data = generator.generate(20, seed=3, mode="mixed")
    flipped = mirror(data, axis)
    np.testing.assert_allclose(world.value_iteration(flipped.rewards, flipped.terminal),
                               flipped.values, atol=1e-4)
    np.testing.assert_array_equal(world.argmax_cells(flipped.values), flipped.goals)
    twice = mirror(flipped, axis)
    np.testing.assert_array_equal(twice.grids, data.grids)
    np.testing.assert_array_equal(twice.goals, data.goals)


def test_direction_words_swap_with_the_flip():
    assert swap_words("Two cells left of the westernmost rock.", SWAP_LEFT_RIGHT) == \
        "two cells right of the easternmost rock"
    assert swap_words("reach the cell above the top-most tree", SWAP_UP_DOWN) == \
        "reach the cell below the bottom most tree"
    assert swap_words("one bellow the northern house", SWAP_UP_DOWN) == \
        "one above the southern house"
    # words without a direction are untouched
    assert swap_words("reach the heart", SWAP_UP_DOWN) == "reach the heart"


def test_with_mirrors_is_four_times_the_data():
    data = generator.generate(5, seed=1, mode="local")
    out = with_mirrors(data)
    assert len(out) == 20
    assert out.grids.shape == (20, *data.grids.shape[1:])
    with pytest.raises(ValueError, match="mirror axis"):
        mirror(data, 0)


def test_every_direction_word_in_puddleworld_train_has_a_mirror(data_dir):
    """A direction word the tables miss would mislabel its mirrored examples."""
    words = {w for task in ("pw-local", "pw-global")
             for text in datasets.load_task(task, "train", data_dir).instructions
             for w in tokenize(text)}
    horizontal = [w for w in words if any(r in w for r in ("left", "right", "east", "west"))
                  and w != "lowest"]
    vertical = [w for w in words if any(r in w for r in
                                        ("above", "below", "bellow", "north", "south", "top",
                                         "bottom", "upper", "lower", "under", "beneath", "up",
                                         "down", "high", "low", "over"))
                and w not in ("highlighting", "yellow")]
    assert not [w for w in horizontal if w not in SWAP_LEFT_RIGHT]
    assert not [w for w in vertical if w not in SWAP_UP_DOWN]
