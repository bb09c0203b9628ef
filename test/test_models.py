# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""Models: the paper's sizes, gradient flow into every module, batching, any map size."""

import numpy as np
import pytest
from spatial_grounding_ros.core.entities import ISI, PUDDLEWORLD
from spatial_grounding_ros.core.text import Vocabulary
from spatial_grounding_ros.data import generator
from spatial_grounding_ros.models.checkpoints import load_checkpoint, save_checkpoint
from spatial_grounding_ros.models.config import (
    head_code_size,
    ModelConfig,
    relation_param_count,
    relative_positions,
)
from spatial_grounding_ros.models.encoders import present_kinds, shifted
from spatial_grounding_ros.models.far import FAR_BEYOND, FAR_REACH, squared_distances
from spatial_grounding_ros.models.head import AxialViews
from spatial_grounding_ros.models.registry import build_model, MODELS
from spatial_grounding_ros.models.relation import split_params, tanh
from spatial_grounding_ros.models.trnet import TRNet
import torch


def test_parameter_vector_sizes_are_the_papers():
    assert relation_param_count(ModelConfig(embed_dim=7)) == 263
    assert relation_param_count(ModelConfig(embed_dim=13)) == 383
    attn = TRNet(ModelConfig(embed_dim=7, vocab_size=10))
    assert attn.decoder.out_features == 263
    assert build_model('t-cnn', ModelConfig(embed_dim=7)).decoder.out_features == 66
    assert build_model('t-cnn', ModelConfig(embed_dim=13)).decoder.out_features == 120


def _batch(n=6, size=10, seed=0):
    data = generator.generate(n, seed=seed, mode='mixed', size=size)
    vocab = Vocabulary.build(data.instructions)
    return (
        data,
        vocab,
        torch.from_numpy(data.grids),
        torch.from_numpy(vocab.encode_batch(data.instructions)),
    )


@pytest.mark.parametrize('name', list(MODELS))
def test_gradient_reaches_every_module(name):
    data, vocab, grids, tokens = _batch()
    torch.manual_seed(0)
    model = build_model(name, ModelConfig(vocab_size=len(vocab)))
    loss = ((model(grids, tokens) - torch.from_numpy(data.values)) ** 2).mean()
    loss.backward()
    for pname, p in model.named_parameters():
        assert p.grad is not None and p.grad.abs().sum() > 0, f'{name}: no gradient in {pname}'


@pytest.mark.parametrize('name', list(MODELS))
def test_batched_equals_one_by_one_and_padding_is_ignored(name):
    data, vocab, grids, tokens = _batch(n=5)
    torch.manual_seed(0)
    model = build_model(name, ModelConfig(vocab_size=len(vocab))).eval()
    with torch.no_grad():
        batched = model(grids, tokens)
        for i in range(len(grids)):
            alone = torch.from_numpy(vocab.encode_batch([data.instructions[i]]))
            torch.testing.assert_close(
                model(grids[i:i + 1], alone)[0], batched[i], atol=1e-5, rtol=1e-4
            )


@pytest.mark.parametrize('shape', [(3, 4), (13, 13), (32, 20)])
def test_any_map_size(shape):
    model = build_model('t-rnet-attn', ModelConfig(vocab_size=5)).eval()
    grids = torch.randint(0, 12, (2, *shape))
    with torch.no_grad():
        values, aux = model(grids, torch.tensor([[2, 3, 4], [2, 0, 0]]), return_aux=True)
    assert values.shape == (2, *shape) and aux['relation_map'].shape == (2, *shape)
    torch.testing.assert_close(aux['attention'].sum(-1), torch.ones(2))
    assert aux['attention'][1, 1:].abs().max() == 0  # no attention on padding


def test_axial_views_are_the_map_wide_maxima_they_name():
    x = torch.randn(2, 3, 5, 7)
    views = AxialViews(x).window(0, 5, 0, 7).unflatten(1, (6, 3))  # (B, view, C, H, W)
    low = x.amin(dim=(2, 3))
    for r in range(5):
        for c in range(7):
            def beyond(part):
                return part.amax(dim=(2, 3)) if part.numel() else low

            expected = [
                x[:, :, r].amax(-1),
                x[:, :, :, c].amax(-1),
                beyond(x[:, :, :, :c]),
                beyond(x[:, :, :, c + 1:]),
                beyond(x[:, :, :r]),
                beyond(x[:, :, r + 1:]),
            ]
            for view, want in enumerate(expected):
                torch.testing.assert_close(views[:, view, :, r, c], want)
    # a window of the map has the map-wide views of its cells
    torch.testing.assert_close(
        AxialViews(x).window(1, 4, 2, 6), AxialViews(x).window(0, 5, 0, 7)[..., 1:4, 2:6]
    )


@pytest.mark.parametrize('shape', [(1, 6), (6, 1), (9, 14)])
def test_axial_head_runs_on_any_map_and_learns_through_the_views(shape):
    model = build_model('t-rnet-attn', ModelConfig(vocab_size=5, axial=True))
    assert model.head.convs[1].in_channels == 8 * 7
    values = model(torch.randint(0, 12, (2, *shape)), torch.tensor([[2, 3, 4], [2, 0, 0]]))
    assert values.shape == (2, *shape)
    values.sum().backward()
    assert model.head.convs[1].weight.grad[:, 8:].abs().sum() > 0


@pytest.mark.parametrize('name', ['t-rnet-attn', 't-rnet'])
def test_far_relation_and_head_text_learn_and_run_on_any_map(name):
    cfg = ModelConfig(vocab_size=5, axial=True, far=True, head_text=True)
    model = build_model(name, cfg)
    assert head_code_size(cfg.head, cfg.head_text) == 3 + 2 * 8 == model.head.code_size
    assert model.decoder.out_features == 263 + 16
    assert model.head.convs[0].in_channels == 3 and model.head.convs[1].in_channels == 8 * 7
    for shape in ((1, 6), (9, 14)):
        values = model(torch.randint(0, 12, (2, *shape)), torch.tensor([[2, 3, 4], [2, 0, 0]]))
        assert values.shape == (2, *shape)
    values.sum().backward()
    # the instruction's scale and shift of the first layer: the decoder's last rows learn
    assert model.decoder.weight.grad[-16:].abs().sum() > 0


@pytest.mark.parametrize('log_cost', [-1.0, -7.0, -12.0])
@pytest.mark.parametrize(
    'shape',
    [(2, 5, 16), (1, 5, 16), (1, 9, 12)],
    ids=['transforms', 'transforms one map', 'pairs'],
)
def test_far_map_is_the_distance_discounted_maximum_over_cell_pairs(log_cost, shape):
    """
    Brute force: every cell i against every cell j within FAR_REACH rows and columns.

    At cost e^-1 the kinds that can raise a cell's floor reach a few cells; at e^-7 the 13
    columns of FAR_REACH bound them on a 16-column map. A map within reach (9x12) takes far_map's
    own every-pair path, the 16-column one its distance transforms.
    """
    torch.manual_seed(3)
    model = build_model('t-rnet', ModelConfig(vocab_size=6, far=True)).eval()
    batch, height, width = shape
    grids = torch.randint(0, 12, shape)
    tokens = torch.tensor([[2, 3, 4], [5, 0, 0]])[:batch]
    with torch.no_grad():
        model.far_log_cost.fill_(log_cost)
        kinds = present_kinds(grids, 12)
        table = model.far_table(model.text(tokens), kinds)
        far = model.far_relation(grids, kinds, table)
    row = {int(k): n for n, k in enumerate(kinds)}
    cost = float(np.exp(log_cost))
    for b in range(batch):
        for r, c in np.ndindex(height, width):
            want = max(
                float(table[b, row[int(grids[b, r, c])], row[int(grids[b, rr, cc])]])
                - cost * ((rr - r) ** 2 + (cc - c) ** 2)
                for rr, cc in np.ndindex(height, width)
                if max(abs(rr - r), abs(cc - c)) <= FAR_REACH
            )
            assert float(far[b, r, c]) == pytest.approx(want, abs=1e-5)
    # and the same gradients, to the table and to the cost, as the maximum over all pairs
    table = table.clone().requires_grad_()
    model.far_relation(grids, kinds, table).sum().backward()
    got = table.grad.clone(), model.far_log_cost.grad.clone()
    table.grad, model.far_log_cost.grad = None, None
    cells = torch.tensor(list(np.ndindex(height, width)))
    offset = cells[:, None] - cells[None]  # (i, j, 2)
    within = offset.abs().amax(-1) <= FAR_REACH
    ids = torch.tensor([row[int(k)] for k in grids.flatten()]).view(batch, -1)
    pairs = torch.stack([table[b][ids[b][:, None], ids[b][None]] for b in range(batch)])
    scores = pairs - model.far_log_cost.exp() * (offset**2).sum(-1)
    scores.masked_fill(~within, float('-inf')).amax(-1).sum().backward()
    torch.testing.assert_close(got[0], table.grad)
    torch.testing.assert_close(got[1], model.far_log_cost.grad)
    # the map is a third input of the head, and it learns through it (at a cost low enough
    # that some cell's maximum is another cell's)
    model.train()
    with torch.no_grad():
        model.far_log_cost.fill_(-5.0)
    model(grids, tokens).sum().backward()
    assert model.head.convs[0].weight.grad[:, 2].abs().sum() > 0
    assert model.far_log_cost.grad != 0
    with pytest.raises(ValueError, match='t-CNN has none'):
        build_model('t-cnn', ModelConfig(vocab_size=6, far=True))


def test_sigmoid_form_tanh_is_tanh():
    """The sigmoid form the relation MLP uses is tanh, in value and in gradient."""
    x = torch.linspace(-12, 12, 2001, dtype=torch.float64, requires_grad=True)
    trained = tanh(x)
    torch.testing.assert_close(trained, torch.tanh(x), rtol=0, atol=1e-15)
    assert torch.autograd.gradcheck(tanh, (x[::50].detach().clone().requires_grad_(),))
    with torch.no_grad():  # no autograd call outside training, the same numbers
        assert torch.equal(tanh(x), trained.detach())


def test_isi_sizes():
    model = build_model(
        't-rnet-attn', ModelConfig(n_entities=len(ISI), embed_dim=ISI.embed_dim, vocab_size=9)
    )
    values = model(torch.randint(0, len(ISI), (2, 13, 13)), torch.randint(1, 9, (2, 7)))
    assert values.shape == (2, 13, 13)


def test_checkpoint_round_trip_and_mismatch_errors(tmp_path):
    data, vocab, grids, tokens = _batch()
    cfg = ModelConfig(vocab_size=len(vocab))
    model = build_model('t-rnet-attn', cfg).eval()
    path = save_checkpoint(
        tmp_path / 'm.pt', 't-rnet-attn', model, cfg, vocab, PUDDLEWORLD, task='test'
    )
    loaded = load_checkpoint(path)  # weights_only=True inside
    assert loaded.header['task'] == 'test' and loaded.vocab.words == vocab.words
    with torch.no_grad():
        torch.testing.assert_close(loaded.model(grids, tokens), model(grids, tokens))
    with pytest.raises(ValueError, match="holds model 't-rnet-attn', not 't-cnn'"):
        load_checkpoint(path, expect_model='t-cnn')
    with pytest.raises(ValueError, match='entity table'):
        load_checkpoint(path, expect_entities=ISI)
    (tmp_path / 'bad.pt').write_bytes(b'garbage')
    with pytest.raises(ValueError, match='bad.pt: not a readable checkpoint'):
        load_checkpoint(tmp_path / 'bad.pt')
    with pytest.raises(FileNotFoundError, match='nope.pt'):
        load_checkpoint(tmp_path / 'nope.pt')
    # a vocabulary of another size than the weights: caught at load time
    blob = torch.load(path, weights_only=True)
    blob['header']['vocabulary'] = blob['header']['vocabulary'] + ['extra']
    torch.save(blob, tmp_path / 'vocab.pt')
    with pytest.raises(ValueError, match='vocab'):
        load_checkpoint(tmp_path / 'vocab.pt')
    # a header without a hyper-parameter is named, never silently defaulted
    blob = torch.load(path, weights_only=True)
    del blob['header']['config']['head_slope']
    torch.save(blob, tmp_path / 'old.pt')
    with pytest.raises(ValueError, match='old.pt: model config lacks head_slope'):
        load_checkpoint(tmp_path / 'old.pt')


def test_unknown_model_name():
    with pytest.raises(ValueError, match="unknown model 'resnet'"):
        build_model('resnet', ModelConfig())


@pytest.mark.parametrize('reference', [True, False])
def test_no_python_loop_over_cells(reference):
    """
    Check that the graph has a fixed number of nodes, whatever the map size.

    Both ways, the pairs (reference) and the relation table (chosen at these sizes).
    """
    model = build_model('t-rnet-attn', ModelConfig(vocab_size=5))
    counts = []
    for size in (16, 32):
        out = model(
            torch.randint(0, 12, (2, size, size)), torch.tensor([[2, 3], [3, 4]]),
            reference=reference,
        )
        seen, stack = set(), [out.grad_fn]
        while stack:
            fn = stack.pop()
            if fn is None or fn in seen:
                continue
            seen.add(fn)
            stack += [f for f, _ in fn.next_functions]
        counts.append(len(seen))
    assert counts[0] == counts[1]


def test_t_rnet_attn_at_zero_attention_is_t_rnet():
    """
    Check a claim of the README.

    README: the attention projection starts at zero, which makes t-RNetAttn exactly t-RNet (uniform
    attention over the words, and the decoder is linear): so the warm-up may run the attention-free
    forward. Same weights, same maps, padding included; and any non-zero attention changes the
    answer (so the comparison can fail).
    """
    data, vocab, grids, tokens = _batch(n=6)
    cfg = ModelConfig(vocab_size=len(vocab))
    torch.manual_seed(0)
    attn = build_model('t-rnet-attn', cfg).eval()
    assert attn.attn.weight.abs().max() == 0  # as built
    rnet = build_model('t-rnet', cfg).eval()
    rnet.load_state_dict({k: v for k, v in attn.state_dict().items() if not k.startswith('attn.')})
    with torch.no_grad():
        expected, expected_aux = rnet(grids, tokens, return_aux=True)
        with_attention, aux = attn(grids, tokens, return_aux=True)
        torch.testing.assert_close(with_attention, expected, rtol=1e-5, atol=1e-6)
        torch.testing.assert_close(
            aux['relation_map'], expected_aux['relation_map'], rtol=1e-5, atol=1e-6
        )
        attn.attention_on = False  # the warm-up's forward
        torch.testing.assert_close(attn(grids, tokens), expected, rtol=0, atol=0)
        attn.attention_on = True
        attn.attn.weight.normal_()
        with pytest.raises(AssertionError):
            torch.testing.assert_close(
                attn(grids, tokens, return_aux=True)[1]['relation_map'],
                expected_aux['relation_map'],
                rtol=1e-5,
                atol=1e-6,
            )


def test_word_matmuls_equal_per_pair_weights():
    """
    Check a claim of the README.

    README: each relation layer applies every word's weights to all pairs in one matmul and mixes
    the results by attention, "same output" as building W_ij = sum_k alpha_ij(k) W(k) per pair.
    Here the per-pair way is written out: the pair's h_ij = sum_k alpha_ij(k) h(k) is decoded to
    its own 263 weights (the paper's formulation) and run through the MLP.
    """
    data, vocab, grids, tokens = _batch(n=3)
    torch.manual_seed(1)
    model = build_model('t-rnet-attn', ModelConfig(vocab_size=len(vocab))).eval()
    with torch.no_grad():
        model.attn.weight.normal_()  # attention that differs by pair and word
        values, aux = model(grids, tokens, return_aux=True)
        # the pairs and their attention, as the paper defines them
        b, h, w = grids.shape
        phi = model.phi(grids)  # (B, H+2, W+2, k)
        phi_i = phi[:, 1:-1, 1:-1].flatten(1, 2)  # (B, N, k)
        phi_j = torch.stack(shifted(phi, 1), 3).flatten(1, 2)  # (B, N, 8, k)
        words, mask, mean = model.text(tokens)
        pair = torch.cat([phi_i.unsqueeze(2).expand_as(phi_j), phi_j], -1)  # [phi_i; phi_j]
        score = torch.einsum('bnpd,bld->bnpl', pair, model.attn(words))
        alpha = score.masked_fill(~mask[:, None, None, :], float('-inf')).softmax(-1)
        h_ij = torch.einsum('bnpl,blh->bnph', alpha, words)  # (B, N, 8, 30)
        # per pair (.., out, in)
        w1, w2, w3 = split_params(model.decoder(h_ij), model.layer_shapes)
        rel = relative_positions(1).expand(b, h * w, -1).unsqueeze(-1)
        x = torch.cat([pair, rel], -1).unsqueeze(-1)  # (B, N, 8, 2k+1, 1)
        r = (w3 @ torch.tanh(w2 @ torch.tanh(w1 @ x))).squeeze(-1).squeeze(-1)
        z1 = r.max(-1).values.view(b, h, w)
        torch.testing.assert_close(aux['relation_map'], z1, rtol=1e-4, atol=1e-5)
        torch.testing.assert_close(
            values,
            model.head(z1, model.decoder(mean)[:, -model.head.code_size:]),
            rtol=1e-4,
            atol=1e-5,
        )
        assert z1.std() > 0.01  # not a degenerate map that any computation would match


@pytest.mark.parametrize('shape', [(2, 3, 7, 9), (1, 2, 150, 170), (1, 1, 1, 40)])
def test_squared_distances_to_the_nearest_mark_within_reach(shape):
    """Both ways of the transform (one op per pass on small planes, shifts on large) are exact."""
    torch.manual_seed(len(shape) + shape[-1])
    marks = torch.rand(shape) < 0.02
    reach = 5
    got = squared_distances(marks, reach).numpy()
    h, w = shape[-2:]
    rows, cols = np.mgrid[0:h, 0:w]
    for index in np.ndindex(*shape[:-2]):
        want = np.full((h, w), FAR_BEYOND)
        for r, c in zip(*np.nonzero(marks[index].numpy())):
            near = (abs(rows - r) <= reach) & (abs(cols - c) <= reach)
            want = np.where(near, np.minimum(want, (rows - r) ** 2 + (cols - c) ** 2), want)
        assert np.array_equal(np.minimum(got[index], FAR_BEYOND), want)


@pytest.mark.parametrize('reference', [False, True])
def test_skip_unknown_reads_past_unknown_words(reference):
    """With skip_unknown, <unk> anywhere in an instruction leaves the value map as it was."""
    torch.manual_seed(0)
    cfg = ModelConfig(vocab_size=9, skip_unknown=True, far=True, head_text=True)
    model = build_model('t-rnet-attn', cfg).eval()
    with torch.no_grad():  # attention that is not uniform, so a word's place matters
        model.attn.weight.normal_()
    grids = torch.randint(0, 12, (3, 6, 7))
    clean = torch.tensor([[4, 5, 6, 7, 0, 0, 0], [8, 2, 0, 0, 0, 0, 0], [3, 0, 0, 0, 0, 0, 0]])
    noisy = torch.tensor([[1, 4, 5, 1, 1, 6, 7], [8, 2, 1, 0, 0, 0, 0], [1, 1, 3, 0, 0, 0, 0]])
    with torch.no_grad():
        before, aux_before = model(grids, clean, return_aux=True, reference=reference)
        after, aux_after = model(grids, noisy, return_aux=True, reference=reference)
    torch.testing.assert_close(after, before, atol=1e-6, rtol=1e-5)
    attention = aux_after['attention']
    assert attention[noisy == 1].abs().max() == 0  # none on the unknown words
    torch.testing.assert_close(attention[noisy > 1], aux_before['attention'][clean > 1])
    # without it, the same weights read <unk> as a word: the map moves
    model.text.skip_unknown = False
    with torch.no_grad():
        assert not torch.allclose(model(grids, noisy, reference=reference), before, atol=1e-4)


@pytest.mark.parametrize('reference', [False, True])
def test_a_name_of_a_kind_the_map_lacks_reads_as_an_unknown_word(reference):
    """With name_words, a name whose kinds are all off the map is passed over; others stay."""
    torch.manual_seed(0)
    # words 5 and 6 name kind 2 (a name and its plural), word 7 kind 3, word 8 kinds 3 and 4
    names = ((), (), (5, 6), (7, 8), (8,)) + ((),) * 7
    cfg = ModelConfig(vocab_size=9, skip_unknown=True, name_words=names, far=True)
    model = build_model('t-rnet-attn', cfg).eval()
    with torch.no_grad():  # attention that is not uniform, so a word's place matters
        model.attn.weight.normal_()
    grids = torch.randint(5, 12, (2, 6, 7))
    grids[:, 1, 1] = 3  # kind 3 on both maps, kind 2 and kind 4 on neither
    clean = torch.tensor([[4, 7, 3, 0, 0], [7, 2, 0, 0, 0]])
    named = torch.tensor([[4, 5, 7, 6, 3], [7, 2, 8, 0, 0]])  # 8 also names kind 3: it stays
    with torch.no_grad():
        before = model(grids, clean, reference=reference)
        after = model(grids, named, reference=reference)
    torch.testing.assert_close(after[0], before[0], atol=1e-6, rtol=1e-5)
    assert not torch.allclose(after[1], before[1], atol=1e-4)
    # on a map that holds kind 2 its names are read: the map moves
    grids[0, 2, 2] = 2
    with torch.no_grad():
        assert not torch.allclose(
            model(grids, named, reference=reference)[0],
            model(grids, clean, reference=reference)[0],
            atol=1e-4,
        )


def test_name_words_survive_a_checkpoint():
    names = ((), (), (5, 6), (7,)) + ((),) * 8
    cfg = ModelConfig(vocab_size=9, skip_unknown=True, name_words=names)
    assert ModelConfig.from_dict(cfg.to_dict()) == cfg
    old = {k: v for k, v in cfg.to_dict().items() if k != 'name_words'}
    assert ModelConfig.from_dict(old).name_words == ()  # a checkpoint from before reads all


def test_skip_unknown_reads_an_all_unknown_instruction_as_one_word():
    torch.manual_seed(0)
    model = build_model('t-rnet-attn', ModelConfig(vocab_size=9, skip_unknown=True)).eval()
    grids = torch.randint(0, 12, (1, 5, 5)).expand(2, -1, -1)
    with torch.no_grad():
        values = model(grids, torch.tensor([[1, 1, 1], [1, 0, 0]]))
    assert torch.isfinite(values).all()
    torch.testing.assert_close(values[0], values[1])  # both read one <unk>
