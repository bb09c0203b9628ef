# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
A model's value maps one map at a time (as the node grounds) equal the same maps in one batch.

`eval` and the robustness study batch their maps; this is what lets their numbers stand for
the model the node runs (the Grounder adds what it does to a map, a landmark table's
translation, the same way batched or not). A batch of one once took a path of its own in the
far relation and dropped every landmark kind but one beyond 13x13 (issue 24).
"""

import numpy as np
import pytest
from spatial_grounding_ros.data.generator import FAMILIES, sample
from spatial_grounding_ros.grounder import Grounder
from spatial_grounding_ros.models.checkpoints import PACKAGED_DIR
from spatial_grounding_ros.models.encoders import unseen_kind_ids
from spatial_grounding_ros.training.supervised import predict_maps
import torch

GRID_CHECKPOINTS = sorted(p.stem for p in PACKAGED_DIR.glob('*.pt') if 'shapeworld' not in p.stem)
# batching changes only the order of float sums (BLAS blocks, LSTM batch): values agree to a
# few ulps of their scale, far below the gap that separates a goal from its neighbours
TOLERANCE = 1e-4


def worlds(grounder: Grounder, size: int, n: int, seed: int):
    """Return n maps of one size with many landmark kinds, and an instruction each."""
    rng = np.random.default_rng([seed, size])
    if grounder.entities.domain == 'puddleworld':
        # every family once or more: several kinds on each map, extremes and 'closest' included
        drawn = [sample(rng, FAMILIES[i % len(FAMILIES)], size) for i in range(n)]
        return np.stack([d[0] for d in drawn]), [d[1] for d in drawn]
    # ISI: random boards of its blocks, and instructions in the checkpoint's own words
    grids = rng.integers(0, len(grounder.entities), (n, size, size))
    words = grounder.vocab.words[2:]
    texts = [' '.join(rng.choice(words, 8)) for _ in range(n)]
    return grids, texts


def one_at_a_time(grounder: Grounder, grids, texts) -> np.ndarray:
    """Value maps the way the node grounds: a text code per instruction, then one map."""
    out = []
    with torch.no_grad():
        for grid, text in zip(grids, texts):
            code = grounder.model.text_code(torch.as_tensor(grounder.vocab.encode_batch([text])))
            out.append(grounder.model.ground(torch.as_tensor(grid)[None], code)[0].numpy())
    return np.stack(out)


@pytest.mark.parametrize('size', [16, 32])
@pytest.mark.parametrize('name', GRID_CHECKPOINTS)
def test_one_map_at_a_time_equals_the_batch(name, size):
    grounder = Grounder.from_checkpoint(name)
    grids, texts = worlds(grounder, size, 12, seed=size)
    assert len(np.unique(grids)) > 4  # several landmark kinds, so the far relation has a choice
    single = one_at_a_time(grounder, grids, texts)
    # the evaluations' path: the full forward over one batch
    batched = predict_maps(grounder.model, grounder.vocab, grids, texts)
    np.testing.assert_allclose(single, batched, rtol=0, atol=TOLERANCE)
    # and the node's fast path over the same batch, every map with its own instruction
    with torch.no_grad():
        code = grounder.model.text_code(torch.as_tensor(grounder.vocab.encode_batch(texts)))
        fast = grounder.model.ground(torch.as_tensor(grids), code).numpy()
    np.testing.assert_allclose(single, fast, rtol=0, atol=TOLERANCE)


@pytest.mark.parametrize('size', [10, 20])
@pytest.mark.parametrize('name', GRID_CHECKPOINTS)
def test_evaluation_batches_equal_batches_of_one_with_unseen_objects(name, size):
    """
    The robustness study's path: value maps of maps holding unseen kinds, batched or not.

    At 10x10 a map alone takes the far relation's every-pair path and a batch its distance
    transforms: the two agree too.
    """
    grounder = Grounder.from_checkpoint(name)
    grids, texts = worlds(grounder, size, 12, seed=size)
    rng = np.random.default_rng(size)
    unseen = unseen_kind_ids(len(grounder.entities), 5)
    for grid in grids:
        grid.reshape(-1)[rng.permutation(grid.size)[:5]] = unseen
    one_at_a_time = predict_maps(grounder.model, grounder.vocab, grids, texts, batch_size=1)
    batched = predict_maps(grounder.model, grounder.vocab, grids, texts)
    np.testing.assert_allclose(one_at_a_time, batched, rtol=0, atol=TOLERANCE)
