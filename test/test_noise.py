# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""The robustness study's noise: what it keeps, what it adds, and the same noise for a seed."""

import numpy as np
import pytest
from spatial_grounding_ros.core.entities import ISI, PUDDLEWORLD
from spatial_grounding_ros.core.text import tokenize, UNK, Vocabulary
from spatial_grounding_ros.data import generator
from spatial_grounding_ros.data.noise import (
    add_noise,
    ARTICLES,
    kind_words,
    MAX_K,
    NOISES,
    referenced_kinds,
    require_unseen_rows,
    VERBS,
)
from spatial_grounding_ros.models.checkpoints import load_checkpoint, save_checkpoint
from spatial_grounding_ros.models.config import ModelConfig
from spatial_grounding_ros.models.encoders import unseen_kind_ids
from spatial_grounding_ros.models.registry import build_model
import torch

UNSEEN = set(unseen_kind_ids(len(PUDDLEWORLD), MAX_K))


@pytest.fixture(scope='module')
def data():
    return generator.generate(60, seed=3, mode='mixed')


@pytest.fixture(scope='module')
def vocab(data):
    return Vocabulary.build(data.instructions + ['go the a'] + list(PUDDLEWORLD.names))


def test_referenced_kinds_rule():
    pw = referenced_kinds('Go to the rocks west of the star.', PUDDLEWORLD)
    assert {PUDDLEWORLD.names[k] for k in pw} == {'rock', 'star'}
    # whole words only: "start" is not a star, "horseshoe" not a horse
    assert referenced_kinds('start at the horseshoe', PUDDLEWORLD) == set()
    isi = referenced_kinds('put the burger king block left of block 12', ISI)
    assert {ISI.names[k] for k in isi} == {'logo_burger_king', 'digit_12'}
    assert kind_words(ISI, ISI.index('logo_coca_cola')) == ['coca', 'cola']


def test_generated_instructions_reference_objects_on_their_map(data):
    """The generator names only objects its map holds, and every instruction names one."""
    for grid, text in zip(data.grids, data.instructions):
        kinds = referenced_kinds(text, PUDDLEWORLD)
        assert kinds, text
        assert kinds <= set(np.unique(grid).tolist()), text


@pytest.mark.parametrize('k', [1, 4, MAX_K])
def test_unseen_objects_keep_goal_and_referenced_objects(data, vocab, k):
    noisy = add_noise(data, vocab, 'obs-noise', k, seed=1)
    for i, (before, after) in enumerate(zip(data.grids, noisy.grids)):
        changed = before != after
        assert changed.sum() == k
        assert set(after[changed].tolist()) <= UNSEEN and len(set(after[changed].tolist())) == k
        assert (before[changed] == generator.GRASS).all()  # free cells only
        assert not changed[tuple(data.goals[i])]
        for kind in referenced_kinds(data.instructions[i], PUDDLEWORLD):
            assert ((before == kind) == (after == kind)).all()
    assert noisy.instructions == data.instructions
    np.testing.assert_array_equal(noisy.values, data.values)  # unseen objects change no reward
    np.testing.assert_array_equal(noisy.goals, data.goals)


@pytest.mark.parametrize('noise', NOISES)
def test_noise_is_reproducible_by_seed_and_nested_in_k(data, vocab, noise):
    def run(k, seed):
        out = add_noise(data, vocab, noise, k, seed)
        return out.grids.tolist(), out.instructions

    assert run(5, 7) == run(5, 7)
    assert run(5, 7) != run(5, 8)
    assert run(0, 7) == (data.grids.tolist(), data.instructions)
    if noise == 'obs-noise':  # the objects at k = 2 are among those at k = 5
        small, large = (np.array(run(k, 7)[0]) for k in (2, 5))
        assert ((small == np.array(data.grids)) | (small == large)).all()


@pytest.mark.parametrize('noise', ['text-noise', 'unknown-words'])
def test_words_go_in_one_run_and_leave_the_instruction_intact(data, vocab, noise):
    k = 3
    noisy = add_noise(data, vocab, noise, k, seed=2)
    for grid, text, new in zip(data.grids, data.instructions, noisy.instructions):
        old, words = tokenize(text), tokenize(new)
        assert len(words) == len(old) + k
        at = next((i for i, (a, b) in enumerate(zip(old, words)) if a != b), len(old))
        # the k words right after the first difference are the inserted ones (the position
        # may sit inside a run of equal words, so find a split that restores the text)
        splits = [j for j in range(at + 1) if words[:j] + words[j + k:] == old]
        assert splits, (text, new)
        inserted = words[splits[-1]:splits[-1] + k]
        if noise == 'unknown-words':
            assert all(vocab.encode(w) == [UNK] for w in inserted)
        else:
            on_map = set(np.unique(grid).tolist()) | referenced_kinds(text, PUDDLEWORLD)
            for w in inserted:
                assert w in vocab.index
                assert w in VERBS + ARTICLES or PUDDLEWORLD.index(w) not in on_map


def test_bad_amounts_and_crowded_maps_are_clear_errors(data, vocab):
    with pytest.raises(ValueError, match='0..10'):
        add_noise(data, vocab, 'obs-noise', MAX_K + 1)
    with pytest.raises(ValueError, match='unknown noise'):
        add_noise(data, vocab, 'static', 1)
    full = data.subset([0])
    full.grids[:] = 8  # rocks everywhere: no free cell
    with pytest.raises(ValueError, match='free cells'):
        add_noise(full, vocab, 'obs-noise', 1)


def test_unseen_rows_are_the_same_in_old_and_new_checkpoints(tmp_path, vocab):
    """A checkpoint from before the unseen rows gets at load time the rows a new model has."""
    torch.manual_seed(0)
    fresh = build_model('t-rnet-attn', ModelConfig(vocab_size=len(vocab)))
    old_cfg = ModelConfig(vocab_size=len(vocab), unseen_kinds=0)
    torch.manual_seed(0)
    old = build_model('t-rnet-attn', old_cfg)
    assert old.phi.embed.num_embeddings == len(PUDDLEWORLD) + 1
    # the unseen rows draw from a generator of their own: the rest of the model is as before
    for key, value in old.state_dict().items():
        torch.testing.assert_close(value, fresh.state_dict()[key][:len(value)])
    path = save_checkpoint(tmp_path / 'old.pt', 't-rnet-attn', old, old_cfg, vocab, PUDDLEWORLD)
    blob = torch.load(path, weights_only=True)
    del blob['header']['config']['unseen_kinds']  # as the shipped checkpoints' headers are
    torch.save(blob, path)
    loaded = load_checkpoint(path).model
    torch.testing.assert_close(loaded.phi.embed.weight, fresh.phi.embed.weight)
    require_unseen_rows(loaded, 't-rnet-attn')


def test_training_never_moves_the_unseen_rows(data, vocab):
    model = build_model('t-cnn', ModelConfig(vocab_size=len(vocab)))
    before = model.phi.embed.weight.detach().clone()
    opt = torch.optim.Adam(model.parameters(), lr=1e-2)
    grids = torch.from_numpy(data.grids)
    tokens = torch.from_numpy(vocab.encode_batch(data.instructions))
    for _ in range(3):
        loss = ((model(grids, tokens) - torch.from_numpy(data.values)) ** 2).mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
    after = model.phi.embed.weight.detach()
    assert not torch.equal(after[:len(PUDDLEWORLD)], before[:len(PUDDLEWORLD)])
    assert torch.equal(after[len(PUDDLEWORLD) + 1:], before[len(PUDDLEWORLD) + 1:])


@pytest.mark.parametrize('name', ['t-rnet-attn', 't-rnet', 't-cnn'])
def test_models_ground_maps_with_unseen_objects(data, vocab, name):
    model = build_model(name, ModelConfig(vocab_size=len(vocab)))
    noisy = add_noise(data, vocab, 'obs-noise', MAX_K, seed=0)
    tokens = torch.from_numpy(vocab.encode_batch(noisy.instructions))
    out = model(torch.from_numpy(noisy.grids), tokens)
    assert out.shape == noisy.values.shape and torch.isfinite(out).all()


def test_a_model_without_unseen_rows_says_so(vocab):
    with pytest.raises(ValueError, match='t-uvfa has no embedding rows for unseen kinds'):
        require_unseen_rows(build_model('t-uvfa', ModelConfig(vocab_size=len(vocab))), 't-uvfa')
