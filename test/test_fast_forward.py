# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The fast forward is the reference forward.

t-RNetAttn and t-RNet read each pair's relation score from a table over (kind_i, kind_j,
offset) per instruction (models.TRNet.text_code and ground); the reference scores every pair of
the map (TRNet.pair_forward). Both must give the same value map, Z1 and attention, and the same
gradients; the tiled output head must give the untiled one bit for bit.
"""

import dataclasses

import numpy as np
import pytest
from spatial_grounding_ros.core.entities import ISI
from spatial_grounding_ros.core.text import Vocabulary
from spatial_grounding_ros.data import generator
from spatial_grounding_ros.grounder import Grounder
from spatial_grounding_ros.models.checkpoints import load_checkpoint, PACKAGED_DIR
from spatial_grounding_ros.models.config import ModelConfig
from spatial_grounding_ros.models.encoders import distractor_kind_ids, kinds_per_map, present_kinds
from spatial_grounding_ros.models.head import gradient_maps
from spatial_grounding_ros.models.registry import build_model
import torch

TOLERANCE = {'rtol': 1e-5, 'atol': 1e-5}
# non-square, 1xN and Nx1, smaller and larger than the kind table (12 x 13 rows)
SHAPES = [(1, 1), (1, 17), (17, 1), (3, 4), (10, 10), (13, 29), (40, 40)]
INSTRUCTIONS = [
    'reach cell two below the westernmost rock',
    'go to the star',
    'reach the cell between diamond and spade and then stop near the house please',
]


def random_model(name: str, vocab_size: int, seed: int, **config) -> torch.nn.Module:
    """Build a seeded model whose attention differs by pair and word (built, it is uniform)."""
    torch.manual_seed(seed)
    model = build_model(name, ModelConfig(vocab_size=vocab_size, **config)).eval()
    if model.capabilities.relation_attention:
        with torch.no_grad():
            model.attn.weight.normal_()
    return model


def inputs(shape: tuple, n_entities: int, seed: int):
    rng = np.random.default_rng(seed)
    vocab = Vocabulary.build(INSTRUCTIONS)
    grids = torch.as_tensor(rng.integers(0, n_entities, (len(INSTRUCTIONS), *shape)))
    grids[0] = 0  # one map of a single kind
    return vocab, grids, torch.as_tensor(vocab.encode_batch(INSTRUCTIONS))


def assert_same(fast, reference):
    (values, aux), (ref_values, ref_aux) = fast, reference
    torch.testing.assert_close(values, ref_values, **TOLERANCE)
    torch.testing.assert_close(aux['relation_map'], ref_aux['relation_map'], **TOLERANCE)
    if ref_aux['attention'] is None:
        assert aux['attention'] is None
    else:
        torch.testing.assert_close(aux['attention'], ref_aux['attention'], **TOLERANCE)


@pytest.mark.parametrize('name', ['t-rnet-attn', 't-rnet'])
@pytest.mark.parametrize('shape', SHAPES)
def test_table_equals_pairs(name, shape):
    """Tables over the kinds present, over all kinds, and forward's choice: all the reference."""
    vocab, grids, tokens = inputs(shape, 12, seed=shape[0] * 100 + shape[1])
    model = random_model(name, len(vocab), seed=len(shape))
    with torch.no_grad():
        reference = model(grids, tokens, return_aux=True, reference=True)
        assert reference[1]['relation_map'].std() > 0.01 or shape == (1, 1)  # not degenerate
        present = present_kinds(grids, 12)
        assert_same(model.ground(grids, model.text_code(tokens, present), True), reference)
        assert_same(model.ground(grids, model.text_code(tokens), True), reference)
        assert_same(model(grids, tokens, return_aux=True), reference)
        # one instruction's code serves a batch of maps
        one = model.text_code(tokens[1:2])
        assert_same(
            model.ground(grids, one, True),
            model(grids, tokens[1:2].expand(len(grids), -1), return_aux=True, reference=True),
        )


def test_table_equals_pairs_isi_and_radius_2():
    """41 kinds with embedding 13 (ISI), the footnote's 24 neighbours, the head's views."""
    for config, n_entities in (
        ({'n_entities': len(ISI), 'embed_dim': ISI.embed_dim}, len(ISI)),
        ({'radius': 2}, 12),
        ({'axial': True, 'head_text': True, 'far': True}, 12),
    ):
        vocab, grids, tokens = inputs((9, 14), n_entities, seed=3)
        model = random_model('t-rnet-attn', len(vocab), seed=4, **config)
        with torch.no_grad():
            assert_same(
                model.ground(grids, model.text_code(tokens), True),
                model(grids, tokens, return_aux=True, reference=True),
            )


@pytest.mark.parametrize('name', ['t-rnet-attn', 't-rnet'])
@pytest.mark.parametrize('size', [10, 24])
def test_table_gradients_equal_pair_gradients(name, size):
    """Training through the table moves every parameter as training through the pairs would."""
    data = generator.generate(8, seed=size, mode='mixed', size=size)
    vocab = Vocabulary.build(data.instructions)
    grids = torch.as_tensor(data.grids)
    tokens = torch.as_tensor(vocab.encode_batch(data.instructions))
    target = torch.as_tensor(data.values)
    model = random_model(name, len(vocab), seed=5).train()
    gradients = []
    for run in (
        lambda: model(grids, tokens, reference=True),
        lambda: model.ground(grids, model.text_code(tokens, present_kinds(grids, 12))),
    ):
        model.zero_grad()
        ((run() - target) ** 2).mean().backward()
        gradients.append({n: p.grad.clone() for n, p in model.named_parameters()})
    reference, fast = gradients
    for pname, grad in reference.items():
        assert grad.abs().sum() > 0, pname
        torch.testing.assert_close(fast[pname], grad, rtol=1e-4, atol=1e-6, msg=pname)


def test_kinds_per_map_are_each_maps_own_then_absent_ones():
    grids = torch.tensor([[[0, 3], [3, 5]], [[7, 7], [7, 7]]])
    kinds = kinds_per_map(grids, n_kinds=13, off_map=12)
    assert kinds.tolist() == [[0, 3, 5], [7, 0, 1]]  # map 1 holds only 7: padded, ascending
    # the off-map kind is never a padding kind, however few kinds are absent
    assert 2 not in kinds_per_map(torch.tensor([[[0]], [[1]]]), n_kinds=3, off_map=2)


@pytest.mark.parametrize('shape', [(9, 12), (11, 14)], ids=['far pairs', 'far transforms'])
def test_per_map_tables_equal_pairs(shape):
    """
    Maps holding different kinds, distractor kinds among them, each get a table of their own.

    The forward's per-map tables (padded to the most kinds a map holds) give the reference's
    values, Z1, attention and gradients, with the far relation on both of its paths.
    """
    vocab, grids, tokens = inputs(shape, 12, seed=13)
    views = {'axial': True, 'head_text': True, 'far': True}
    model = random_model('t-rnet-attn', len(vocab), seed=14, distractor_kinds=4, **views)
    distractors = distractor_kind_ids(model.cfg)
    with torch.no_grad():  # training redraws these rows at every step; here, once
        model.phi.embed.weight[distractors] = torch.randn(len(distractors), model.cfg.embed_dim)
    grids[1] = grids[1] % 3
    grids[1, :3, :3] = distractors[0]
    grids[2, 4, 5] = distractors[3]
    kinds = kinds_per_map(grids, model.phi.embed.num_embeddings, model.phi.off_map)
    assert kinds[0, 0] == 0 and (kinds[1, :4] == torch.tensor([0, 1, 2, distractors[0]])).all()
    assert model.phi.off_map not in kinds
    with torch.no_grad():
        assert_same(
            model(grids, tokens, return_aux=True),
            model(grids, tokens, return_aux=True, reference=True),
        )
    target = torch.randn(len(grids), *shape)
    gradients = []
    for reference in (True, False):
        model.zero_grad()
        ((model(grids, tokens, reference=reference) - target) ** 2).mean().backward()
        gradients.append({n: p.grad.clone() for n, p in model.named_parameters()})
    for name, grad in gradients[0].items():
        torch.testing.assert_close(gradients[1][name], grad, rtol=1e-4, atol=1e-6, msg=name)


def test_t_cnn_text_code_serves_any_map():
    vocab, grids, tokens = inputs((6, 11), 12, seed=6)
    model = random_model('t-cnn', len(vocab), seed=7)
    with torch.no_grad():
        expected = model(grids, tokens[2:3].expand(len(grids), -1), return_aux=True)
        assert_same(model.ground(grids, model.text_code(tokens[2:3]), True), expected)


def test_table_without_a_kind_of_the_grid_is_an_error():
    vocab, grids, tokens = inputs((5, 5), 12, seed=8)
    model = random_model('t-rnet-attn', len(vocab), seed=9)
    grids[:, 0, 0] = 11
    code = model.text_code(tokens, torch.arange(11))
    with pytest.raises(ValueError, match=r'lacks entity kinds \[11\]'):
        model.ground(grids, code)


HEAD_VIEWS = [
    {},
    {'axial': True},
    {'axial': True, 'head_text': True, 'far': True},
]


@pytest.mark.parametrize('views', HEAD_VIEWS, ids=['plain', 'axial', 'far'])
@pytest.mark.parametrize('shape', [(30, 45), (1, 40), (61, 13), (7, 7)])
def test_tiled_head_is_the_untiled_head(shape, views):
    """
    Tiles with a halo of one cell per 3x3 convolution: the same numbers, bit for bit.

    With map-wide views, the views come from the whole map's earlier layers.
    """
    head = random_model('t-rnet-attn', 5, seed=10, **views).head
    z1, code = torch.randn(2, *shape), torch.randn(2, head.code_size)
    far = torch.randn(2, *shape) if views.get('far') else None
    with torch.no_grad():
        untiled = head(z1, code, far)
        for tile in (5, 8):
            head.tile = tile
            assert torch.equal(head(z1, code, far), untiled), tile
        if views:
            return
        beta = code
        # the halo is what makes it exact: 5x5 tiles convolved on their own differ
        x = torch.stack([z1, torch.einsum('bc,chw->bhw', beta, gradient_maps(*shape))], 1)
        no_halo = torch.cat(
            [
                torch.cat(
                    [head.convolve(x[:, :, r:r + 5, c:c + 5]) for c in range(0, shape[1], 5)], 2
                )
                for r in range(0, shape[0], 5)
            ],
            1,
        )
        assert no_halo.shape == untiled.shape and not torch.equal(no_halo, untiled)


GRID_CHECKPOINTS = sorted(
    p.stem for p in PACKAGED_DIR.glob('*.pt') if not p.name.startswith('shapeworld_')
)


@pytest.mark.parametrize('checkpoint', GRID_CHECKPOINTS)
def test_shipped_checkpoint_fast_equals_reference(checkpoint):
    """
    The node's fast path (a text code kept per instruction) gives the reference's maps.

    For every shipped model, on maps of all its kinds; and the Grounder computes the code of
    an instruction once for the three maps.
    """
    grounder = Grounder(load_checkpoint(checkpoint))
    model = grounder.model
    rng = np.random.default_rng(11)
    # a word of the vocabulary that reads as a place to go (an intent with a text code)
    instruction = next(w for w in grounder.vocab.words[2:] if grounder.read(w).intent == 'go')
    tokens = torch.as_tensor(grounder.vocab.encode_batch([instruction]))
    for shape in ((10, 10), (1, 23), (33, 20)):
        grid = torch.as_tensor(rng.integers(0, len(grounder.entities), shape))[None]
        with torch.no_grad():
            fast, fast_aux = model.ground(grid, model.text_code(tokens), return_aux=True)
            values, aux = model(
                grid,
                tokens,
                return_aux=True,
                **({'reference': True} if hasattr(model, 'pair_forward') else {}),
            )
        np.testing.assert_allclose(fast.numpy(), values.numpy(), **TOLERANCE)
        np.testing.assert_allclose(
            fast_aux['relation_map'].numpy(), aux['relation_map'].numpy(), **TOLERANCE
        )
        if aux['attention'] is not None:
            np.testing.assert_allclose(fast_aux['attention'], aux['attention'], **TOLERANCE)
        grounder.ground(grid[0].numpy(), instruction)
    assert len(grounder.text_codes) == 1  # computed once, for the three maps


def test_grounder_keeps_recent_instructions_only():
    grounder = Grounder(load_checkpoint('pw_t-rnet-attn'), cached_instructions=2)
    grid = generator.generate(1, seed=12, mode='mixed').grids[0]
    first = grounder.ground(grid, 'reach the star')
    grounder.ground(grid, 'reach the rock')
    grounder.ground(grid, 'reach the star')  # used again: now the most recent
    tree = grounder.ground(grid, 'reach the tree')
    # keyed by what the network reads ("reach cell with star": places.surface)
    assert list(grounder.text_codes) == [first.model_instruction, tree.model_instruction]
    np.testing.assert_array_equal(grounder.ground(grid, 'reach the star').values, first.values)


@pytest.mark.parametrize('shape', [(40, 40), (33, 70), (1, 1100), (1100, 1), (2, 600)])
def test_axial_views_convolved_as_profiles_are_the_joined_views(shape):
    """Inference convolves a view's row or column profile: the sums training convolves joined."""
    head = random_model('t-rnet-attn', 5, seed=11, axial=True, far=True).head
    z1, code, far = torch.randn(2, *shape), torch.randn(2, head.code_size), torch.randn(2, *shape)
    with torch.no_grad():
        profiles = head(z1, code, far)
    joined = head(z1, code, far).detach()  # with gradients: the views joined to the channels
    torch.testing.assert_close(profiles, joined, atol=1e-5, rtol=1e-5)


def test_the_shared_caches_serve_training_after_inference():
    """The Grounder grounds in inference mode; a map size it cached first still trains."""
    vocab, grids, tokens = inputs((13, 17), 12, seed=12)
    model = random_model('t-rnet-attn', len(vocab), seed=13, axial=True, far=True)
    with torch.inference_mode():
        model(grids, tokens)  # fills gradient_maps and pair_distances for 13x17
    model(grids, tokens).sum().backward()
    assert all(p.grad is not None for p in model.head.parameters())


@pytest.mark.parametrize('shape', [(64, 65), (70, 90)])
def test_large_maps_gather_offset_by_offset_as_training_gathers_them_all(shape):
    """Past GATHER_BY_OFFSET_CELLS inference gathers offset by offset: the same Z1, attention."""
    from spatial_grounding_ros.models.map_cells import GATHER_BY_OFFSET_CELLS

    assert shape[0] * shape[1] > GATHER_BY_OFFSET_CELLS
    vocab, grids, tokens = inputs(shape, 12, seed=14)
    model = random_model('t-rnet-attn', len(vocab), seed=15, axial=True, far=True)
    code = model.text_code(tokens)
    with torch.inference_mode():
        values, aux = model.ground(grids, code, return_aux=True)
    trained, trained_aux = model.ground(grids, code, return_aux=True)  # gradients on
    assert torch.equal(aux['relation_map'], trained_aux['relation_map'].detach())
    assert torch.equal(aux['attention'], trained_aux['attention'].detach())
    torch.testing.assert_close(values, trained.detach(), **TOLERANCE)


def test_kept_map_cells_ground_as_computed_and_each_map_keeps_its_own():
    """A map's table rows are kept at inference: the same groundings, each map its own."""
    from spatial_grounding_ros.models import map_cells

    vocab, grids, tokens = inputs((10, 10), 12, seed=17)
    model = random_model('t-rnet-attn', len(vocab), seed=18, axial=True, far=True)
    maps = [grids[n:n + 1] for n in range(len(grids))]
    with torch.inference_mode():
        code = model.text_code(tokens[:1])
        map_cells._KEPT.clear()
        # each map twice, the second from the kept rows: what the maps computed afresh give
        kept = [model.ground(m, code, True) for m in maps + maps]
        assert len(map_cells._KEPT) == len(maps)
        fresh = []
        for m in maps:
            map_cells._KEPT.clear()
            fresh.append(model.ground(m, code, True))
    for (values, aux), (ref_values, ref_aux) in zip(kept, fresh + fresh):
        assert torch.equal(values, ref_values)
        assert torch.equal(aux['relation_map'], ref_aux['relation_map'])
        assert torch.equal(aux['attention'], ref_aux['attention'])
    # a table per map (a batch's kinds_per_map) and a forward with gradients keep nothing
    map_cells._KEPT.clear()
    with torch.inference_mode():
        model(grids, tokens)
    model.ground(maps[1], model.text_code(tokens[:1]))
    assert not map_cells._KEPT
    # a kind the table lacks is an error each time, not a kept row
    with torch.inference_mode(), pytest.raises(ValueError, match='lacks entity kinds'):
        model.ground(maps[1], dataclasses.replace(code, kinds=code.kinds[:3]))


@pytest.mark.parametrize('views', [{}, {'axial': True, 'head_text': True, 'far': True}])
@pytest.mark.parametrize('shape', [(1, 1), (1, 17), (3, 4), (10, 10), (13, 29), (32, 32)])
def test_traced_head_is_the_head(shape, views, monkeypatch):
    """A small map's head runs as a trace at inference: bit for bit the head as written."""
    from spatial_grounding_ros.models import head as heads, traces

    head = random_model('t-rnet-attn', 5, seed=16, **views).head
    for b in (1, 3):  # one map, and a map with its mirror images
        z1, code = torch.randn(b, *shape), torch.randn(b, head.code_size)
        far = torch.randn(b, *shape) if head.inputs == 3 else None
        with torch.inference_mode():
            traced = head(z1, code, far)
            monkeypatch.setattr(heads, 'TRACED_CELLS', 0)
            written = head(z1, code, far)
            monkeypatch.undo()
        assert torch.equal(traced, written), b
    assert traces.traces_of(head) == 2  # one per shape


def test_a_traced_head_follows_its_own_weights_only():
    """Trained in place, a head's trace follows; a copy's trace never reads the original's."""
    import copy
    from spatial_grounding_ros.models import traces

    head = random_model('t-rnet-attn', 5, seed=17, axial=True, head_text=True, far=True).head
    z1, code, far = torch.randn(1, 10, 10), torch.randn(1, head.code_size), torch.randn(1, 10, 10)
    with torch.no_grad():
        before = head(z1, code, far)
        copied = copy.deepcopy(head)
        copied.convs[0].weight.mul_(2)  # as an optimizer step changes it: in place
        assert torch.equal(head(z1, code, far), before)
        changed = copied(z1, code, far)
        assert not torch.equal(changed, before)
        head.convs[0].weight.mul_(2)
        assert torch.equal(head(z1, code, far), changed)
        for size in range(2, 4 + traces.TRACES_KEPT):  # the oldest traces go
            head(torch.randn(1, 1, size), code, torch.randn(1, 1, size))
    assert traces.traces_of(head) == traces.TRACES_KEPT


@pytest.mark.parametrize('name, views', [
    ('t-rnet-attn', {'axial': True, 'head_text': True, 'far': True, 'skip_unknown': True}),
    ('t-rnet-attn', {}),
    ('t-rnet', {'far': True}),
])
def test_traced_text_code_is_the_text_code(name, views):
    """A grounder's text code (all kinds, no gradients) runs as a trace: bit for bit."""
    from spatial_grounding_ros.models import traces

    model = random_model(name, 9, seed=18, **views)
    codes = 0
    # t-RNetAttn also as its warm-up epochs run it, without attention
    for attention in {model.capabilities.relation_attention, False}:
        model.attention_on = attention
        for length in (1, 3, 7):
            for b in (1, 4):  # one wording, and a map's with its mirror images
                seeded = torch.Generator().manual_seed(length)
                tokens = torch.randint(0, 9, (b, length), generator=seeded)  # pads, unknowns
                with torch.inference_mode():
                    traced = model.text_code(tokens)
                    written = model.compute_text_code(tokens)
                codes += 1
                for field in ('kinds', 'relations', 'attention', 'head', 'far'):
                    a, w = getattr(traced, field), getattr(written, field)
                    assert (a is None) == (w is None), field
                    assert a is None or torch.equal(a, w), field
    assert traces.traces_of(model) == codes  # one per shape (and attention switch)
    # with gradients (training) and per map's kinds (a batch's forward): as written
    tokens = torch.randint(0, 9, (2, 5))
    assert model.text_code(tokens).relations.requires_grad
    assert traces.traces_of(model) == codes
