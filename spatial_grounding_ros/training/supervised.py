# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Supervised training and evaluation, readable top to bottom.

The loss is the value-map MSE plus a goal-cell cross-entropy, minimised by Adam at the paper's
learning rate; a validation split carved out of train (by world) selects the checkpoint; the
test split is only ever evaluated.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
import time

import numpy as np
import torch
from tqdm import tqdm

from . import distributed
from .epochs import Epochs, trim_padding
from .recipe import recipe, TrainConfig
from ..core import tasks, world
from ..core.tasks import SYNTHETIC_SIZES
from ..core.text import Vocabulary
from ..data.augment import with_mirrors
from ..data.datasets import (
    GroundingSet,
    load_task,
    load_world_instructions,
    pw_world_ids,
    split_by_world,
)
from ..data.generator import generate, MODES
from ..data.noise import kind_word_ids
from ..data.paraphrase import paraphrased
from ..models.checkpoints import load_checkpoint, save_checkpoint
from ..models.config import ModelConfig
from ..models.registry import build_model


@torch.no_grad()
def predict_maps(
    model, vocab: Vocabulary, grids: np.ndarray, instructions: list[str], batch_size: int = 512
) -> np.ndarray:
    """Predict value maps (N, H, W) for grids (N, H, W) and one instruction each."""
    model.eval()
    grids = torch.from_numpy(np.asarray(grids, dtype=np.int64))
    tokens = torch.from_numpy(vocab.encode_batch(instructions))
    out = [
        model(grids[i:i + batch_size], trim_padding(tokens[i:i + batch_size]))
        for i in range(0, len(grids), batch_size)
    ]
    return torch.cat(out).numpy()


def predict(model, vocab: Vocabulary, data: GroundingSet, batch_size: int = 512) -> np.ndarray:
    """Predict value maps (N, H, W) for a data set."""
    return predict_maps(model, vocab, data.grids, data.instructions, batch_size)


def evaluate(model, vocab: Vocabulary, data: GroundingSet) -> dict:
    pred = predict(model, vocab, data)
    return world.evaluate_maps(pred, data.values, data.rewards, data.terminal)


def evaluate_hit(model, vocab: Vocabulary, data: GroundingSet) -> float:
    """Return the exact-goal rate alone (no score iteration): cheap enough for every epoch."""
    return float(np.mean((world.argmax_cells(predict(model, vocab, data)) == data.goals).all(1)))


def training_parts(
    task: tasks.Task,
    train: GroundingSet,
    val: GroundingSet,
    tc: TrainConfig,
    data_dir: str | Path,
    sizes: tuple = SYNTHETIC_SIZES,
) -> list[GroundingSet]:
    """
    Return what a task trains on, one GroundingSet per map size.

    The human examples (with their mirror images), the training worlds' pickle instructions,
    generated worlds.
    """
    human = with_mirrors(train) if tc.mirrors else train
    parts = [human]
    if tc.world_instructions:
        held_out = set(val.worlds)
        worlds = pw_world_ids(data_dir, task.pw_modes)
        parts.append(load_world_instructions(data_dir, [w for w in worlds if w not in held_out]))
    for n, size, count in per_size(tc.synthetic or 0, sizes):
        seed = 10_000 + 100 * tc.seed + n
        generated = generate(count, seed=seed, mode=tc.generator_mode, size=size)
        parts.append(paraphrased(generated, tc.paraphrase or 0.0, seed))
    # one set per map size, so that a batch holds maps of one size
    by_size: dict[tuple, list[GroundingSet]] = {}
    for part in parts:
        by_size.setdefault(part.grids.shape[1:], []).append(part)
    return [GroundingSet.concat(task.name, group) for group in by_size.values()]


def per_size(total: int, sizes: tuple = SYNTHETIC_SIZES) -> list[tuple[int, int, int]]:
    """Split `total` generated worlds over `sizes`' (map size, share): (index, size, count > 0)."""
    counts = [(n, size, int(round(total * share))) for n, (size, share) in enumerate(sizes)]
    return [(n, size, count) for n, size, count in counts if count]


def late_parts(tc: TrainConfig, sizes: tuple = SYNTHETIC_SIZES) -> list[GroundingSet]:
    """Return the generated row-col worlds of `tc.late_row_col`, one set per map size."""
    return [
        generate(count, seed=30_000 + 100 * tc.seed + n, mode='training', size=size,
                 families=('row-col',))
        for n, size, count in per_size(tc.late_row_col or 0, sizes)
    ]


def generated_validation(
    mode: str | None, seed: int, per_family: int = 40
) -> GroundingSet | None:
    """Fresh generated worlds (never trained on) of every family of generator mode `mode`."""
    if mode is None:
        return None
    return generate(per_family * len(MODES[mode]), seed=20_000 + seed, mode=mode)


def start_from(model, cfg: ModelConfig, vocab: Vocabulary, checkpoint: str) -> None:
    """Load a checkpoint's weights into `model`, whose config and vocabulary must be its."""
    loaded = load_checkpoint(checkpoint)
    # name_words is set once training ends (skip_absent_names): a run starts without it
    if loaded.vocab.words != vocab.words or replace(loaded.model.cfg, name_words=()) != cfg:
        raise ValueError(
            f'--init {checkpoint}: its config or vocabulary differs from this run; '
            'fine-tune with the task and options it was trained with'
        )
    model.load_state_dict(loaded.model.state_dict())


def best_epoch(
    epochs: Epochs,
    bar,
    vocab: Vocabulary,
    val: GroundingSet,
    val_generated: GroundingSet | None,
) -> tuple[tuple, list[tuple]]:
    """
    Run every epoch of `bar`, validating each; return the best and the history.

    The best is (score, state dict, epoch) by `select`: the second half's best validation
    PQ plus generated-validation HIT (ties: MSE), or the lowest validation MSE of all epochs.
    The history holds (training loss, validation MSE, PQ, generated HIT) per epoch.
    """
    model, tc = epochs.model, epochs.tc
    best = ((float('inf'),), None, -1)
    history = []
    for epoch in bar:
        loss = epochs.run(epoch)
        val_metrics = evaluate(model, vocab, val)
        val_hit = evaluate_hit(model, vocab, val_generated) if val_generated is not None else 0.0
        history.append((loss, val_metrics['mse'], val_metrics['pq'], val_hit))
        score = (
            (-(val_metrics['pq'] + val_hit), val_metrics['mse'])
            if tc.select == 'pq'
            else (val_metrics['mse'],)
        )
        # PQ of a few hundred maps swings while the maps are still rough (PW: validation PQ
        # 0.937 at epoch 5 of 40, MSE 0.373), so PQ only chooses among the second half
        if score < best[0] and (tc.select != 'pq' or epoch >= tc.epochs // 2):
            best = (score, {k: v.clone() for k, v in model.state_dict().items()}, epoch)
        bar.set_postfix(
            train=f'{loss:.3f}',
            val_mse=f'{val_metrics["mse"]:.3f}',
            val_pq=f'{val_metrics["pq"]:.3f}',
            gen_hit=f'{val_hit:.3f}',
            best=best[2],
            scale=f'{epochs.goal_log_scale.exp().item():.1f}',
        )
    return best, history


def train_supervised(
    task: str,
    model_name: str,
    data_dir: str | Path,
    out: str | Path,
    tc: TrainConfig = TrainConfig(),
    train_data: GroundingSet | None = None,
    progress: bool = True,
    **model_options,
) -> tuple[Path, dict]:
    """
    Train `model_name` on `task`, keep the epoch with the best validation score.

    Writes `out/<task>_<model>.pt`; returns its path and a summary. Under `torchrun
    --nproc_per_node N` each process runs a share of every batch (distributed.py); only the
    first prints progress and writes the checkpoint.
    """
    run = recipe(task, model_name, tc, **model_options)  # every setting, resolved (recipe.py)
    tc = run.train
    torch.manual_seed(tc.seed)
    torch.set_num_threads(tc.threads)
    data = train_data if train_data is not None else load_task(task, 'train', data_dir)
    train, val = split_by_world(data, tc.val_fraction, tc.seed)
    parts = training_parts(tasks.task(task), train, val, tc, data_dir, run.synthetic_sizes)
    late = late_parts(tc, run.synthetic_sizes)  # trained on from epoch late_from * epochs on
    val_generated = generated_validation(tc.generator_mode, tc.seed) if tc.synthetic else None
    # from everything trained on: generated phrasing and the mirrors' swapped direction words
    vocab = Vocabulary.build(
        list(data.instructions) + [t for p in parts + late for t in p.instructions]
    )
    cfg = replace(
        run.model_config,
        n_entities=len(data.entities),
        vocab_size=len(vocab),
        embed_dim=data.entities.embed_dim,
    )
    model = build_model(model_name, cfg)
    if tc.init:
        start_from(model, cfg, vocab, tc.init)
    processes = distributed.start()
    epochs = Epochs(
        model, parts + late, vocab, tc, processes, (len(parts), int(tc.epochs * tc.late_from))
    )
    start = time.perf_counter()
    bar = tqdm(
        range(tc.epochs),
        desc=f'{task} {model_name}',
        disable=not (progress and processes.main),
        unit='ep',
    )
    best, history = best_epoch(epochs, bar, vocab, val, val_generated)
    train_seconds = time.perf_counter() - start
    model.load_state_dict(best[1])
    if tc.skip_absent_names:  # after training: the epochs and their validation are untouched
        cfg = replace(cfg, name_words=kind_word_ids(data.entities, vocab))
        model.cfg = cfg
    val_metrics = evaluate(model, vocab, val)
    if val_generated is not None:
        val_metrics['generated_hit'] = evaluate_hit(model, vocab, val_generated)
    n_train = sum(len(p) for p in parts + late)
    summary = {
        'task': task,
        'train_examples': n_train,
        'val_examples': len(val),
        'best_epoch': best[2],
        'epochs': tc.epochs,
        'train_seconds': round(train_seconds, 1),
        'val': val_metrics,
        'train_config': vars(tc).copy(),
        # the whole run, the model's config as trained (value_map.json's rows keep it)
        'recipe': replace(run, model_config=cfg).to_dict(),
    }
    # every process validated the same weights; one writes them
    path = Path(out) / f'{task}_{model_name}.pt'
    if processes.main:
        save_checkpoint(
            path,
            model_name,
            model,
            cfg,
            vocab,
            data.entities,
            task=task,
            training_data=f'{data.name} ({n_train} train / {len(val)} validation, by world)',
            seed=tc.seed,
            best_epoch=best[2],
            val_metrics=val_metrics,
            goal_scale=round(float(epochs.goal_log_scale.detach().exp()), 3),
            train_seconds=summary['train_seconds'],
            train_config=vars(tc).copy(),
            loss_history=[[round(x, 5) for x in row] for row in history],
            **({'processes': processes.size} if processes.size > 1 else {}),
        )
    distributed.finish(processes)
    return path, summary
