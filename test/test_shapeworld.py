# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
ShapeWorld: the generator's invariants, the noise, both models learning, the commands.

Truth is checked by a reader of the statements written here from the task's definition (centres
compared along the relation's axis), not by the generator's own `truth`.
"""

import json
import re

import numpy as np
import pytest
from spatial_grounding_ros import cli
from spatial_grounding_ros.core.text import Vocabulary
from spatial_grounding_ros.models.checkpoints import load_checkpoint
from spatial_grounding_ros.shapeworld import data as sw
from spatial_grounding_ros.shapeworld.models import build_model, pair_offsets, ShapeWorldConfig
from spatial_grounding_ros.shapeworld.training import as_input, encode, load, train, TrainConfig
import torch
import torch.nn.functional as F

N = 400


@pytest.fixture(autouse=True)
def one_thread():
    """One torch thread: on a busy 2-core machine a second one waits more than it works."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


@pytest.fixture(scope='module')
def data():
    return sw.generate(N, seed=7)


def boxes(objects):
    return [tuple(o) for o in objects if o[0] >= 0]


def test_scenes_have_4_or_5_objects_apart_from_each_other(data):
    for objects in data.objects:
        objs = boxes(objects)
        assert len(objs) in (4, 5)
        for n, (shape, colour, x0, y0, size) in enumerate(objs):
            assert 0 <= shape < 8 and 0 <= colour < 8
            assert 0 <= x0 and x0 + size <= 64 and 0 <= y0 and y0 + size <= 64
            for _, _, x1, y1, size1 in objs[n + 1:]:
                apart_x = x0 + size + sw.GAP <= x1 or x1 + size1 + sw.GAP <= x0
                apart_y = y0 + size + sw.GAP <= y1 or y1 + size1 + sw.GAP <= y0
                assert apart_x or apart_y


def test_images_show_the_objects_in_their_colours(data):
    for image, objects in zip(data.images[:50], data.objects[:50]):
        covered = np.zeros((64, 64), dtype=bool)
        for shape, colour, x0, y0, size in boxes(objects):
            box = image[y0:y0 + size, x0:x0 + size].astype(float)
            lit = box.max(-1) > 0
            assert lit.mean() > 0.3, 'an object covers a good part of its box'
            rgb = np.array(sw.COLOURS[sw.COLOUR_NAMES[colour]])
            mean = box[lit].mean(0) / 255
            # the colour up to the object's shade
            assert np.allclose(mean / mean.max(), rgb / rgb.max(), atol=0.02)
            covered[y0:y0 + size, x0:x0 + size] = True
        assert image[~covered].max() == 0, 'black outside the objects'


SENTENCE = re.compile(
    r'an? (?:(\w+) )?(\w+) is (to the left of|to the right of|above|below) an? (?:(\w+) )?(\w+)$'
)


def read(text):
    """((shape, colour), relation, (shape, colour)) by name, None where not named."""
    colour1, noun1, relation, colour2, noun2 = SENTENCE.match(text).groups()

    def description(colour, noun):
        if noun in sw.COLOURS:  # only a colour word is never the noun...
            raise AssertionError(text)
        return (None if noun == 'shape' else noun, colour)

    return description(colour1, noun1), relation, description(colour2, noun2)


def fits(obj, description):
    shape, colour = description
    return (shape is None or sw.SHAPES[obj[0]] == shape) and (
        colour is None or sw.COLOUR_NAMES[obj[1]] == colour
    )


def named(description):
    """Return the words a description names, shape and colour, None left out."""
    return {w for w in description if w is not None}


def check_statement(text, label, objects, reason):
    """
    Read one statement against its scene, from the task's definition, and check its label.

    True: objects fit both sides, the relation holds for some pair. False for its reason:
    'relation' (both sides fit objects, the relation holds for no pair), 'subject' or
    'reference' (no object fits that side, some object fits the other).
    """
    subject, relation, reference = read(text)
    objs = boxes(objects)
    a = [o for o in objs if fits(o, subject)]
    b = [o for o in objs if fits(o, reference)]
    assert not [o for o in a if fits(o, reference)], f'{text}: no object is both'
    # one side's words within the other's: such a statement could never be true
    assert not named(subject) <= named(reference), text
    assert not named(reference) <= named(subject), text
    assert bool(label) == (reason == 'true'), (text, reason)
    if reason == 'subject':
        assert not a and b, f'{text}: no {subject}, but a {reference}'
        return
    if reason == 'reference':
        assert a and not b, f'{text}: a {subject}, but no {reference}'
        return
    assert reason in ('true', 'relation') and a and b, f'{text}: both objects exist'
    axis = 0 if 'left' in relation or 'right' in relation else 1
    sign = -1 if relation in ('to the left of', 'above') else 1

    def centre(o):
        return o[2 + axis] + (o[4] - 1) / 2

    holds = any(sign * (centre(p) - centre(q)) > 0 for p in a for q in b)
    assert holds == bool(label), text
    assert all(abs(centre(p) - centre(q)) >= sw.MARGIN for p in a for q in b)


def test_labels_are_true_to_the_scene_and_each_false_one_for_its_reason(data):
    for text, label, objects, reason in zip(
        data.statements, data.labels, data.objects, data.reasons
    ):
        check_statement(text, label, objects, reason)


def test_false_statements_come_from_the_three_sources_in_their_mix(data):
    false = [r for r, label in zip(data.reasons, data.labels) if not label]
    assert set(false) == {'relation', 'subject', 'reference'}
    n = len(false)
    shares = {
        'relation': 1 - sw.ABSENT,
        'subject': sw.ABSENT * sw.SUBJECT,
        'reference': sw.ABSENT * (1 - sw.SUBJECT),
    }
    for reason, share in shares.items():
        got = false.count(reason)
        assert abs(got - n * share) < 5 * np.sqrt(n * share * (1 - share)), (reason, got)
    # the changed attribute is sometimes one the image has: both words name something in the
    # image, never together ("a red square" beside a red circle and a blue square)
    binding = 0
    for text, objects, reason in zip(data.statements, data.objects, data.reasons):
        if reason in ('subject', 'reference'):
            shape, colour = read(text)[0 if reason == 'subject' else 2]
            objs = boxes(objects)
            binding += bool(
                shape and colour
                and any(sw.SHAPES[o[0]] == shape for o in objs)
                and any(sw.COLOUR_NAMES[o[1]] == colour for o in objs)
            )
    assert binding >= 5


def test_labels_are_balanced_overall_and_per_kind_of_statement(data):
    assert data.labels.mean() == 0.5
    by_relation, by_kinds = {}, {}
    for text, label in zip(data.statements, data.labels):
        subject, relation, reference = read(text)
        by_relation.setdefault(relation, []).append(label)
        kinds = tuple((s is None, c is None) for s, c in (subject, reference))
        by_kinds.setdefault(kinds, []).append(label)
    assert set(by_relation) == set(sw.RELATIONS)
    for labels in [*by_relation.values(), *by_kinds.values()]:
        # about 100 each by relation, 44 by kinds: 5 standard deviations from a half
        assert abs(np.mean(labels) - 0.5) < 5 * 0.5 / np.sqrt(len(labels)), labels
    kinds = {(s is None, c is None) for text in data.statements for s, c in read(text)[::2]}
    assert kinds == {(False, True), (True, False), (False, False)}, 'shape, colour and both'


def test_curriculum_statements_name_both_objects_by_colour_only():
    data = sw.generate(200, seed=3, descriptions=('colour',))
    assert data.labels.mean() == 0.5
    for text in data.statements:
        subject, _, reference = read(text)
        assert subject[0] is None and reference[0] is None, text
        assert subject[1] and reference[1], text
    with pytest.raises(ValueError, match='descriptions'):
        sw.generate(2, descriptions=('size',))


@pytest.mark.parametrize('absent, reasons', [
    (1.0, {'subject', 'reference'}),  # the warm-up: every false one names an absent object
    (0.0, {'relation'}),  # the previous data: every false one plausible
])
def test_false_statements_of_one_kind_only(absent, reasons):
    data = sw.generate(200, seed=4, absent=absent)
    assert data.labels.mean() == 0.5
    assert {r for r, label in zip(data.reasons, data.labels) if not label} == reasons
    for text, label, objects, reason in zip(
        data.statements, data.labels, data.objects, data.reasons
    ):
        check_statement(text, label, objects, reason)
    with pytest.raises(ValueError, match='fraction'):
        sw.generate(2, absent=1.5)


def test_generation_is_seeded_and_cached(tmp_path):
    a = sw.load_split('test', tmp_path, n=30)
    [path] = tmp_path.glob('*.npz')
    assert path.name == f'shapeworld-v{sw.VERSION}-test-absent0.667-30-seed0.npz'
    assert sw.load_split('test', tmp_path, n=30, absent=0).reasons.count('relation') == 15
    path = tmp_path / path.name
    before = path.stat().st_mtime_ns
    b = sw.load_split('test', tmp_path, n=30)
    assert path.stat().st_mtime_ns == before, 'the second call reads the file'
    assert np.array_equal(a.images, b.images) and a.statements == b.statements
    assert a.reasons == b.reasons and set(a.reasons) == set(sw.REASONS)
    assert np.array_equal(a.images, sw.generate(30, seed=sw.SPLIT_SEEDS['test']).images)
    train_split = sw.load_split('train', tmp_path, n=30)
    assert train_split.statements != a.statements, 'splits come from different streams'
    path.write_bytes(b'garbage')
    with pytest.raises(ValueError, match='corrupt ShapeWorld cache'):
        sw.load_split('test', tmp_path, n=30)
    with pytest.raises(ValueError, match='no split'):
        sw.load_split('dev', tmp_path)


def test_noise_leaves_objects_and_statement_words_in_place(data):
    rng = np.random.default_rng(0)
    noisy = sw.image_noise(data.images[:20], data.objects[:20], 5, rng)
    clean = data.images[:20].astype(np.float32) / 255
    for n in range(20):
        for _, _, x0, y0, size in boxes(data.objects[n]):
            box = np.s_[y0:y0 + size, x0:x0 + size]
            assert np.array_equal(noisy[n][box], clean[n][box])
        changed = (noisy[n] != clean[n]).any(-1).sum()
        assert changed >= 4 * sw.NOISE_PATCH**2, 'five patches (a few values may be exactly 0)'
    texts = sw.text_noise(data.statements[:20], 3, np.random.default_rng(0))
    for noisy_text, text in zip(texts, data.statements[:20]):
        words = noisy_text.split()
        assert len(words) == len(text.split()) + 3
        inserted = [w for w in words if w not in text.split() or w in sw.NOISE_WORDS]
        assert len(inserted) >= 3
    assert sw.text_noise(['a b'], 0, rng) == ['a b']


def test_results_tables_show_each_reason_and_the_all_plausible_split():
    """reproduce.markdown_tables: one row a model, its accuracy on each reason, both splits."""
    from spatial_grounding_ros.shapeworld.reproduce import markdown_tables, NOISE_KS

    by = {r: {'acc': 0.5, 'n': 10} for r in sw.REASONS}
    rows = [{
        'model': m, 'epochs': 13, 'train_seconds': 60.0,
        'test': {'acc': acc, 'n': 40, 'by_reason': by},
        'test_plausible': {'acc': 0.625, 'n': 40},
    } for m, acc in (('t-vgg', 0.55), ('t-rnet-attn', 0.875))]
    noise = [{'model': m, 'noise': kind, 'k': k, 'acc': 0.5, 'n': 40}
             for m in ('t-vgg', 't-rnet-attn') for kind in ('image', 'text') for k in NOISE_KS]
    main, noisy = markdown_tables(rows, noise)
    header, rule, vgg, rnet = [line for line in main.splitlines() if line.startswith('|')]
    cells = [c.strip() for c in vgg.strip('|').split('|')]
    names = [c.strip() for c in header.strip('|').split('|')]
    assert len(cells) == len(names) == rule.count('---')
    row = dict(zip(names, cells))
    assert (row['ACC ours'], row['n'], row['all-plausible test']) == ('0.550', '40', '0.625')
    assert row['false: no subject (n)'] == '0.500 (10)' and row['train min'] == '1.0'
    assert rnet.startswith('| t-rnet-attn | 0.875 | 0.72 |')
    assert noisy.count('\n| image |') == len(NOISE_KS)


def test_relation_scores_each_pair_at_its_offset():
    model = build_model('t-rnet-attn', ShapeWorldConfig(vocab_size=5))
    assert model.grid == 8
    offsets = model.offset_table[model.offset_index]  # (N, N, 2): j from i, (d_col, d_row)
    torch.testing.assert_close(offsets, pair_offsets(8))
    # cell 9 is (col 1, row 1), cell 10 one to the right, cell 17 one below
    assert offsets[9, 10].tolist() == pytest.approx([1 / 7, 0])
    assert offsets[9, 17].tolist() == pytest.approx([0, 1 / 7])


def fit(model, loss_fn, steps: int = 12) -> list[float]:
    """
    Take `steps` Adam steps on loss_fn(); return each step's loss.

    On eight examples: memorising them is enough to see a model learn.
    """
    opt = torch.optim.Adam(model.parameters(), lr=1e-3)
    losses = []
    for _ in range(steps):
        loss = loss_fn()
        opt.zero_grad()
        loss.backward()
        opt.step()
        losses.append(loss.item())
    return losses


def test_scene_attributes_by_hand():
    """Which shapes, colours and shape-colour pairs an image holds: t-VGG's scene labels."""
    square, circle = sw.SHAPES.index('square'), sw.SHAPES.index('circle')
    red, blue = sw.COLOUR_NAMES.index('red'), sw.COLOUR_NAMES.index('blue')
    objects = np.full((2, 5, 5), -1, dtype=np.int64)
    objects[0, 0, :2] = square, red
    objects[0, 1, :2] = circle, blue
    objects[0, 2, :2] = circle, red
    objects[1, 0, :2] = circle, blue  # one object; the other rows are -1: no object
    got = sw.scene_attributes(objects)
    n_s, n_c = len(sw.SHAPES), len(sw.COLOUR_NAMES)
    assert got.shape == (2, sw.N_ATTRIBUTES) == (2, 8 + 8 + 64)

    def pair(shape, colour):
        return n_s + n_c + shape * n_c + colour

    first = {square, circle, n_s + red, n_s + blue,
             pair(square, red), pair(circle, blue), pair(circle, red)}
    assert set(np.flatnonzero(got[0])) == first
    assert set(np.flatnonzero(got[1])) == {circle, n_s + blue, pair(circle, blue)}


def test_vgg_reads_the_scene_and_the_scene_loss_trains_it(data):
    """t-VGG's scene head, from the image alone, learns which objects are there."""
    torch.manual_seed(0)
    vocab = Vocabulary.build(data.statements)
    model = build_model('t-vgg', ShapeWorldConfig(vocab_size=len(vocab)))
    x, t = as_input(data.images[:8]), encode(vocab, data.statements[:8])
    scene = torch.from_numpy(sw.scene_attributes(data.objects[:8]))
    losses = fit(model, lambda: F.binary_cross_entropy_with_logits(
        model(x, t, return_aux=True)[1]['scene'], scene
    ))
    assert losses[-1] < 0.8 * losses[0], losses
    # the scene is the image's: the statement does not change it
    _, a = model(x, t, return_aux=True)
    _, b = model(x, t.flip(0), return_aux=True)
    torch.testing.assert_close(a['scene'], b['scene'])


@pytest.mark.parametrize('name', ['t-rnet-attn', 't-vgg'])
def test_model_trains_and_its_loss_falls(name, data):
    torch.manual_seed(0)
    vocab = Vocabulary.build(data.statements)
    model = build_model(name, ShapeWorldConfig(vocab_size=len(vocab)))
    x, t = as_input(data.images[:8]), encode(vocab, data.statements[:8])
    y = torch.from_numpy(data.labels[:8])
    losses = fit(model, lambda: F.cross_entropy(model(x, t), y))
    assert losses[-1] < 0.8 * losses[0], losses
    logits, aux = model(x, t, return_aux=True)
    assert logits.shape == (8, 2)


def test_train_and_eval_commands(tmp_path, capsys):
    path, summary = train(
        't-rnet-attn',
        tmp_path,
        TrainConfig(epochs=1, train_size=40, warmup_size=20, warmup_epochs=1, batch_size=16),
        cache_dir=tmp_path,
        progress=False,
    )
    assert path.name == 'shapeworld_t-rnet-attn.pt' and summary['val_examples'] == 4
    # one warm-up epoch over 20 colour-named statements, one over the 36 training examples
    assert summary['epochs'] == 2 and summary['train_steps'] == 2 + 3
    argv = ['shapeworld-eval', '--checkpoint', str(path), '--split', 'test',
            '--cache', str(tmp_path), '--json']
    assert cli.main(argv) == 0
    clean = json.loads(capsys.readouterr().out)
    assert clean['n'] == 500 and 0 <= clean['acc'] <= 1
    assert clean['model'] == 't-rnet-attn'
    assert cli.main(argv + ['--image-noise', '2', '--text-noise', '3']) == 0
    noisy = json.loads(capsys.readouterr().out)
    assert (noisy['image_noise'], noisy['text_noise'], noisy['n']) == (2, 3, 500)
    # a ShapeWorld checkpoint is not a grid model, and the other way round: one clear line
    with pytest.raises(ValueError, match='holds a ShapeWorld image classifier'):
        load_checkpoint(path)
    with pytest.raises(ValueError, match='not a ShapeWorld image classifier'):
        load('pw_t-rnet-attn')
    # usage mistakes: argparse's one line and exit status 2
    for mistake in (['--image-noise', '-1'], ['--split', 'dev']):
        with pytest.raises(SystemExit) as stop:
            cli.main(argv[:-1] + mistake)
        assert stop.value.code == 2
    with pytest.raises(SystemExit) as stop:
        cli.main(['shapeworld-train', '--model', 't-cnn'])
    assert stop.value.code == 2 and "invalid choice: 't-cnn'" in capsys.readouterr().err


def test_train_command_sets_every_config_field(tmp_path, capsys):
    """`shapeworld-train` options reach the run: the header's train_config holds them."""
    argv = ['shapeworld-train', '--model', 't-vgg', '--out', str(tmp_path), '--cache',
            str(tmp_path), '--epochs', '1', '--train-size', '40', '--warmup-size', '20',
            '--warmup-epochs', '1', '--batch-size', '16', '--max-minutes', '0', '--seed', '3']
    assert cli.main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary['checkpoint'] == str(tmp_path / 'shapeworld_t-vgg.pt')
    assert summary['epochs'] == 2 and not summary['stopped_at_time_limit']
    _, _, header = load(summary['checkpoint'])
    config = header['train_config']
    assert (config['warmup_size'], config['max_minutes'], config['seed']) == (20, 0.0, 3)
    assert config == {**vars(TrainConfig(
        epochs=1, train_size=40, warmup_size=20, warmup_epochs=1, batch_size=16, max_minutes=0,
        seed=3,
    ))}


def test_train_command_refuses_torchrun(monkeypatch, capsys):
    """Refuse shapeworld-train under torchrun: each copy would train and write the same file."""
    monkeypatch.setenv('WORLD_SIZE', '2')
    assert cli.main(['shapeworld-train', '--model', 't-vgg']) == 2
    assert 'not under torchrun' in capsys.readouterr().err
