# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Supervised training's README rules, on real (tiny) training runs.

The kept epoch is the second half's best validation PQ (ties: MSE), `--select mse` the lowest
validation MSE of all epochs; validation holds out whole PuddleWorld worlds.
"""

from dataclasses import replace

import numpy as np
import pytest
from spatial_grounding_ros.data import datasets
from spatial_grounding_ros.data.augment import add_distractors
from spatial_grounding_ros.data.generator import generate
from spatial_grounding_ros.models.checkpoints import load_checkpoint
from spatial_grounding_ros.models.config import ModelConfig
from spatial_grounding_ros.models.encoders import distractor_kind_ids
from spatial_grounding_ros.models.registry import build_model
from spatial_grounding_ros.training.supervised import train_supervised, TrainConfig
import torch

EPOCHS = 6


def one_epoch(**changes) -> TrainConfig:
    """One epoch on the training data given, in batches of 16, nothing added to it."""
    return TrainConfig(
        epochs=1, batch_size=16, synthetic=0, mirrors=False, world_instructions=False,
        goal_weight=0.0, threads=1, **changes,
    )


def tiny_run(tmp_path, seed: int, select: str) -> dict:
    """
    6 epochs of t-CNN on 160 generated worlds (no data download), at lr 0.05.

    Too large on purpose, so that validation swings from epoch to epoch as it does early in a real
    run, and the epochs the rules pick differ. Returns the checkpoint's header.
    """
    tc = TrainConfig(
        epochs=EPOCHS,
        batch_size=16,
        lr=0.05,
        synthetic=0,
        mirrors=False,
        world_instructions=False,
        goal_weight=0.0,
        select=select,
        seed=seed,
        threads=1,
    )
    path, summary = train_supervised(
        'pw-local',
        't-cnn',
        '',
        tmp_path / f'{select}{seed}',
        tc,
        train_data=generate(160, seed=seed, mode='local'),
        progress=False,
    )
    header = load_checkpoint(path).header
    assert header['best_epoch'] == summary['best_epoch']
    # the weights kept are the chosen epoch's: evaluated again, they give its history entry
    _, val_mse, val_pq, _ = header['loss_history'][header['best_epoch']]  # gen. HIT: 0, none here
    assert round(header['val_metrics']['mse'], 5) == val_mse
    assert round(header['val_metrics']['pq'], 5) == val_pq
    return header


def test_kept_epoch_is_the_second_halfs_best_validation_pq_or_the_lowest_mse(tmp_path):
    """
    Check which epoch is kept when the best PQ falls in the first half.

    On runs whose best PQ of all epochs falls in the first half (found among the first
    seeds), the kept epoch is still the second half's best PQ; with --select mse, on a run
    whose lowest MSE falls in the first half, that first-half epoch is kept.
    """
    seen = {'pq': False, 'mse': False}
    for seed in range(6):
        pq_run, mse_run = tiny_run(tmp_path, seed, 'pq'), tiny_run(tmp_path, seed, 'mse')
        history = pq_run['loss_history']
        assert mse_run['loss_history'] == history  # selection does not change training
        mses, pqs = [h[1] for h in history], [h[2] for h in history]
        # --select pq: the best validation PQ + generated HIT (no generated worlds here: 0)
        # among epochs 3..5, the lower MSE among equal scores
        scores = [h[2] + h[3] for h in history]
        second = range(EPOCHS // 2, EPOCHS)
        best = max(scores[e] for e in second)
        tied = [e for e in second if scores[e] == best]
        assert pq_run['best_epoch'] == min(tied, key=lambda e: mses[e])
        # --select mse: the lowest MSE of all epochs
        assert mse_run['best_epoch'] == int(np.argmin(mses))
        seen['pq'] |= int(np.argmax(pqs)) < EPOCHS // 2
        seen['mse'] |= int(np.argmin(mses)) < EPOCHS // 2
        if all(seen.values()):
            break
    assert all(seen.values()), f'no run told the rules apart: {seen}'


@pytest.mark.parametrize('task, worlds', [('pw-local', 54), ('pw-global', 117), ('pw', 171)])
def test_puddleworld_validation_holds_out_whole_worlds(data_dir, task, worlds):
    """
    Check a claim of the README.

    README: validation is 10% of the training *worlds*, and no map is shared with training: every
    instruction of a world falls on one side.
    """
    data = datasets.load_task(task, 'train', data_dir)
    assert len(set(data.worlds)) == worlds
    train, val = datasets.split_by_world(data, 0.1, seed=0)
    assert len(train) + len(val) == len(data)
    assert len(set(val.worlds)) == round(0.1 * worlds)
    assert not set(train.worlds) & set(val.worlds)
    assert not {g.tobytes() for g in train.grids} & {g.tobytes() for g in val.grids}


def test_training_validates_on_the_world_split(data_dir, tmp_path):
    """train_supervised's validation set is split_by_world's (one epoch on PW local)."""
    tc = TrainConfig(
        epochs=1, synthetic=0, mirrors=False, world_instructions=False, seed=2, threads=1
    )
    path, summary = train_supervised('pw-local', 't-cnn', data_dir, tmp_path, tc, progress=False)
    train, val = datasets.split_by_world(
        datasets.load_task('pw-local', 'train', data_dir), 0.1, seed=2
    )
    assert (summary['train_examples'], summary['val_examples']) == (len(train), len(val))
    assert (
        load_checkpoint(path)
        .header['training_data']
        .endswith(f'({len(train)} train / {len(val)} validation, by world)')
    )


def test_distractors_stand_on_free_cells_and_are_redrawn_every_step():
    cfg = ModelConfig(vocab_size=4, distractor_kinds=4)
    model = build_model('t-rnet-attn', cfg)
    ids = distractor_kind_ids(cfg)
    assert ids[0] == cfg.n_entities + 1 + cfg.unseen_kinds  # after the unseen rows, never them
    data = generate(40, seed=1, mode='local')
    grids, goals = torch.from_numpy(data.grids), torch.from_numpy(data.goals)
    unseen = model.phi.embed.weight[cfg.n_entities + 1:ids[0]].detach().clone()
    first = add_distractors(model, grids, goals, 4, np.random.default_rng(0))
    rows = model.phi.embed.weight[ids].detach().clone()
    again = add_distractors(model, grids, goals, 4, np.random.default_rng(0))
    assert torch.equal(first, again)  # seeded
    assert torch.equal(model.phi.embed.weight[ids], rows)
    add_distractors(model, grids, goals, 4, np.random.default_rng(1))
    assert not torch.equal(model.phi.embed.weight[ids], rows)  # redrawn
    assert torch.equal(model.phi.embed.weight[cfg.n_entities + 1:ids[0]], unseen)
    changed = first != grids
    assert torch.isin(first[changed], torch.tensor(ids)).all()
    assert (grids[changed] == 0).all()  # only free cells
    assert changed.flatten(1).sum(1).max() <= 4 and changed.any()
    for grid, goal in zip(first, goals):
        assert grid[tuple(goal)] not in ids
    with pytest.raises(ValueError, match='5 distractors need as many'):
        add_distractors(model, grids, goals, 5, np.random.default_rng(0))


def test_training_with_distractors_keeps_the_unseen_rows_untouched(tmp_path):
    tc = one_epoch(distractors=3)
    path, _ = train_supervised(
        'pw-local', 't-rnet-attn', '', tmp_path, tc,
        train_data=generate(60, seed=2, mode='local'), progress=False,
    )
    model = load_checkpoint(path).model
    cfg = model.cfg
    assert cfg.distractor_kinds == 3
    fresh = build_model('t-rnet-attn', cfg)
    unseen = slice(cfg.n_entities + 1, cfg.n_entities + 1 + cfg.unseen_kinds)
    torch.testing.assert_close(model.phi.embed.weight[unseen], fresh.phi.embed.weight[unseen])
    trained = slice(0, cfg.n_entities + 1)
    assert not torch.equal(model.phi.embed.weight[trained], fresh.phi.embed.weight[trained])


def test_t_uvfa_trains_without_distractors_on_a_task_that_has_them(tmp_path):
    """The pw task's distractors apply to models with distractor rows; t-UVFA has none."""
    tc = one_epoch()
    data = generate(40, seed=3, mode='local')
    path, _ = train_supervised('pw', 't-uvfa', '', tmp_path, tc, train_data=data, progress=False)
    assert load_checkpoint(path).header['config']['distractor_kinds'] == 0
    with pytest.raises(ValueError, match='t-uvfa has no distractor kinds'):
        train_supervised(
            'pw', 't-uvfa', '', tmp_path, replace(tc, distractors=2), train_data=data,
            progress=False,
        )


@pytest.mark.parametrize('paper_model', [False, True])
def test_paper_model_drops_the_tasks_additions(tmp_path, paper_model):
    """`--paper-model` trains the paper's t-RNetAttn on a task whose model has additions."""
    tc = one_epoch(paper_model=paper_model)
    path, _ = train_supervised(
        'pw-local', 't-rnet-attn', '', tmp_path, tc,
        train_data=generate(40, seed=4, mode='local'), progress=False,
    )
    cfg = load_checkpoint(path).model.cfg
    assert (cfg.axial, cfg.far, cfg.head_text) == ((False,) * 3 if paper_model else (True,) * 3)


def test_text_noise_trains_and_is_recorded(tmp_path):
    """The header and the summary record the run; the summary's recipe (value_map.json's rows)."""
    tc = one_epoch(text_noise=3)
    path, summary = train_supervised(
        'pw-local', 't-rnet-attn', '', tmp_path, tc,
        train_data=generate(40, seed=6, mode='local'), progress=False,
    )
    loaded = load_checkpoint(path)
    assert loaded.header['train_config']['text_noise'] == 3
    recipe = summary['recipe']
    assert recipe['train'] == loaded.header['train_config']
    assert recipe['model_config'] == loaded.model.cfg.to_dict()  # as trained: its vocabulary
    assert recipe['train']['noise_share'] == 0.5 and recipe['data']['synthetic_sizes']


def test_skip_absent_names_is_set_once_trained_and_leaves_the_weights_as_they_were(tmp_path):
    """The epochs read instructions as written: the weights are those of the run without it."""
    data = generate(40, seed=6, mode='local')
    paths = {}
    for on in (False, True):
        tc = one_epoch(skip_unknown=True, skip_absent_names=on)
        paths[on], _ = train_supervised(
            'pw-local', 't-rnet-attn', '', tmp_path / str(on), tc, train_data=data,
            progress=False,
        )
    off, on = (load_checkpoint(paths[k]) for k in (False, True))
    for name, weights in off.model.state_dict().items():
        assert torch.equal(weights, on.model.state_dict()[name]), name
    assert off.model.cfg.name_words == ()
    words = on.vocab.words
    rock = on.entities.index('rock')
    assert {words[i] for i in on.model.cfg.name_words[rock]} <= {'rock', 'rocks', 'rockes'}
    assert 'rock' in {words[i] for i in on.model.cfg.name_words[rock]}
    with pytest.raises(ValueError, match='t-cnn does not read it'):
        train_supervised(
            'pw-local', 't-cnn', '', tmp_path, one_epoch(skip_absent_names=True),
            train_data=data, progress=False,
        )


def test_text_noise_waits_for_the_attention():
    """
    t-RNetAttn's warm-up epochs read clean instructions; noise words come with the attention.

    The warm-up's uniform average over the words cannot pass over a word, and noise there
    cost "closest" (docs/robustness.md).
    """
    from spatial_grounding_ros.core.text import UNK, Vocabulary
    from spatial_grounding_ros.training.distributed import Group
    from spatial_grounding_ros.training.epochs import Epochs

    data = generate(64, seed=8, mode='local')
    vocab = Vocabulary.build(data.instructions)
    cfg = ModelConfig(n_entities=len(data.entities), vocab_size=len(vocab))
    model = build_model('t-rnet-attn', cfg)
    unknown = {False: [], True: []}  # attention on -> whether each batch read an <unk>
    model.register_forward_pre_hook(
        lambda m, inputs: unknown[m.attention_on].append(bool((inputs[1] == UNK).any()))
    )
    tc = replace(one_epoch(text_noise=10), epochs=2, attention_warmup=0.5, noise_share=0.5)
    run = Epochs(model, [data], vocab, tc, Group())
    run.run(0)
    run.run(1)
    assert unknown[False] and not any(unknown[False])  # the warm-up: clean
    assert sum(unknown[True]) >= 2  # with the attention: noise (half the instructions)


def test_late_row_col_worlds_join_at_the_late_epoch():
    """
    --late-row-col: generated row-col worlds, every map size, read from --late-from on only.

    Row-col through the whole run cost the human global split (docs/landmarks.md).
    """
    from spatial_grounding_ros.core.text import Vocabulary
    from spatial_grounding_ros.training.distributed import Group
    from spatial_grounding_ros.training.epochs import Epochs
    from spatial_grounding_ros.training.supervised import late_parts

    late = late_parts(TrainConfig(late_row_col=200, seed=0))
    assert [p.grids.shape[1] for p in late] == [10, 16, 24]
    assert [len(p) for p in late] == [150, 34, 16]
    assert all(' and ' in t for p in late for t in p.instructions)  # a row and a column
    assert late_parts(TrainConfig()) == []
    data = generate(64, seed=8, mode='local')
    vocab = Vocabulary.build(data.instructions + [t for p in late for t in p.instructions])
    cfg = ModelConfig(n_entities=len(data.entities), vocab_size=len(vocab))
    model = build_model('t-cnn', cfg)
    sizes = {False: set(), True: set()}  # epoch >= 1 -> the map sizes its batches held
    epoch = [0]
    model.register_forward_pre_hook(
        lambda m, inputs: sizes[epoch[0] >= 1].add(inputs[0].shape[-1])
    )
    run = Epochs(model, [data, *late], vocab, replace(one_epoch(), epochs=2), Group(), (1, 1))
    run.run(0)
    epoch[0] = 1
    run.run(1)
    assert sizes == {False: {10}, True: {10, 16, 24}}


def test_init_starts_from_a_checkpoints_weights_and_refuses_another_config():
    import torch

    from spatial_grounding_ros.core.text import Vocabulary
    from spatial_grounding_ros.models.checkpoints import load_checkpoint
    from spatial_grounding_ros.models.registry import build_model
    from spatial_grounding_ros.training.supervised import start_from

    loaded = load_checkpoint('pw_t-rnet-attn')
    # the default reads past absent names, set once its training ended; a run starts without
    assert loaded.model.cfg.name_words
    cfg = replace(loaded.model.cfg, name_words=())
    model = build_model('t-rnet-attn', cfg)
    start_from(model, cfg, loaded.vocab, 'pw_t-rnet-attn')
    for name, value in loaded.model.state_dict().items():
        assert torch.equal(model.state_dict()[name], value), name
    other = Vocabulary(loaded.vocab.words[2:] + ['zebra'])
    with pytest.raises(ValueError, match='--init'):
        start_from(model, cfg, other, 'pw_t-rnet-attn')
    with pytest.raises(ValueError, match='--init'):
        start_from(model, replace(cfg, skip_unknown=False), loaded.vocab, 'pw_t-rnet-attn')
