# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Supervised training and evaluation, readable top to bottom.

Supervised training (value-map MSE plus a goal-cell cross-entropy) and evaluation,
readable top to bottom.

Adam at the paper's learning rate; a validation split carved out of train (by world)
selects the checkpoint; the test split is only ever evaluated.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from pathlib import Path
import time

import numpy as np
import torch
import torch.nn.functional as F
from tqdm import tqdm

from . import distributed
from .options import check, option
from ..core import tasks, world
from ..core.text import Vocabulary
from ..data.augment import add_distractors, insert_noise_words, noise_word_pools, with_mirrors
from ..data.datasets import (
    GroundingSet,
    load_task,
    load_world_instructions,
    pw_world_ids,
    split_by_world,
)
from ..data.generator import generate, MODES
from ..data.noise import MAX_K
from ..models.checkpoints import save_checkpoint
from ..models.config import ModelConfig
from ..models.registry import build_model

# (map size, share of the generated examples): most at Janner's 10x10, some larger so that
# references that span the map (extremes, gradients) learn how they scale.
SYNTHETIC_SIZES = ((10, 0.75), (16, 0.17), (24, 0.08))


@dataclass
class TrainConfig:
    """
    Training hyper-parameters, each declared once: `train` makes its options of them.

    A field left at None takes the task's value (tasks.py). Adam at the paper's lr 1e-3; batch
    64, not the paper's 512: PW local has ~1400 training maps, so 512 gives 3 steps an epoch, and
    on a CPU budget the number of steps, not the batch, is what limits the fit.
    """

    epochs: int | None = option(None, "training epochs (default: the task's)", low=1)
    batch_size: int = option(64, 'examples per optimizer step', low=1)
    lr: float = option(1e-3, 'Adam learning rate at the start', low=0.0)
    lr_final: float = option(1e-4, 'learning rate at the end of the cosine decay', low=0.0)
    val_fraction: float = option(
        0.1, 'share of the training worlds held out for validation', low=0.01, high=0.9
    )
    attention_warmup: float | None = option(
        None,
        'share of epochs t-RNetAttn trains with (still uniform) attention off (default: the '
        "task's)",
        low=0.0,
        high=1.0,
    )
    synthetic: int | None = option(
        None,
        'generated PuddleWorld examples added to training, all families, mixed sizes (default: '
        "the task's)",
        low=0,
    )
    world_instructions: bool | None = option(
        None, "add the training worlds' synthetic pickle instructions (default: the task's)"
    )
    mirrors: bool | None = option(
        None, "add mirrored copies of the human training examples (default: the task's)"
    )
    distractors: int | None = option(
        None,
        'up to this many distractor objects on free cells of each training map, of kinds whose '
        "embeddings are redrawn from N(0, 1) every step (0: none; default: the task's)",
        low=0,
        high=MAX_K,  # as many as the robustness study's unseen objects
    )
    text_noise: int | None = option(
        None,
        'up to this many noise words (unknown words, verbs, articles, absent object names) at '
        "one position of half the training instructions (0: none; default: the task's)",
        low=0,
        high=MAX_K,  # as many as the robustness study inserts
    )
    goal_weight: float | None = option(
        None, "weight of the goal-cell cross-entropy beside the MSE (default: the task's)",
        low=0.0,
    )
    goal_scale: float = option(
        5.0, "the values times this are the goal cross-entropy's logits (at the start)",
        low=0.01,
    )
    learn_goal_scale: bool = option(False, "learn the goal logits' temperature")
    select: str = option(
        'pq', 'keep the epoch of the second half with the best validation PQ plus '
        'generated-validation HIT (ties: MSE), or the lowest MSE of all epochs',
        choices=('pq', 'mse'),
    )
    paper_model: bool = option(
        False,
        "the paper's model, without the task's additions (tasks.py: axial views, far relation, "
        'instruction in the head)',
    )
    seed: int = option(0, 'seed of the weights, the split and the batches', low=0, high=2**32 - 1)
    threads: int = option(2, 'torch threads', low=1)

    def __post_init__(self):
        check(self)

    def for_task(self, task: str) -> 'TrainConfig':
        """Return this config with every field left at None set to `task`'s value."""
        settings = tasks.task(task)
        return replace(
            self,
            **{
                f.name: getattr(settings, f.name)
                for f in fields(self)
                if getattr(self, f.name) is None
            },
        )


def encode(vocab: Vocabulary, data: GroundingSet) -> tuple[torch.Tensor, torch.Tensor]:
    return torch.from_numpy(data.grids), torch.from_numpy(vocab.encode_batch(data.instructions))


def batches(lengths: np.ndarray, batch_size: int, rng: np.random.Generator) -> list[np.ndarray]:
    """
    Return shuffled batches of similar instruction length.

    Sorted by length within pools of 8 batches, so padding, which the per-pair attention
    pays for, stays short.
    """
    order = rng.permutation(len(lengths))
    pool = batch_size * 8
    out = []
    for i in range(0, len(order), pool):
        chunk = order[i:i + pool]
        chunk = chunk[np.argsort(lengths[chunk], kind='stable')]
        out += [chunk[j:j + batch_size] for j in range(0, len(chunk), batch_size)]
    return [out[i] for i in rng.permutation(len(out))]


def _trim(tokens: torch.Tensor) -> torch.Tensor:
    """Drop padding columns that no row of this batch uses."""
    used = int((tokens != 0).any(0).nonzero().max()) + 1 if (tokens != 0).any() else 1
    return tokens[:, :used]


@torch.no_grad()
def predict_maps(
    model, vocab: Vocabulary, grids: np.ndarray, instructions: list[str], batch_size: int = 512
) -> np.ndarray:
    """Predict value maps (N, H, W) for grids (N, H, W) and one instruction each."""
    model.eval()
    grids = torch.from_numpy(np.asarray(grids, dtype=np.int64))
    tokens = torch.from_numpy(vocab.encode_batch(instructions))
    out = [
        model(grids[i:i + batch_size], _trim(tokens[i:i + batch_size]))
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
    task: str, train: GroundingSet, val: GroundingSet, tc: TrainConfig, data_dir: str | Path
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
        worlds = pw_world_ids(data_dir, tasks.task(task).pw_modes)
        parts.append(load_world_instructions(data_dir, [w for w in worlds if w not in held_out]))
    if tc.synthetic:
        for n, (size, share) in enumerate(SYNTHETIC_SIZES):
            count = int(round(tc.synthetic * share))
            if count:
                parts.append(
                    generate(
                        count,
                        seed=10_000 + 100 * tc.seed + n,
                        mode=tasks.task(task).generator_mode,
                        size=size,
                    )
                )
    # one set per map size, so that a batch holds maps of one size
    by_size: dict[tuple, list[GroundingSet]] = {}
    for part in parts:
        by_size.setdefault(part.grids.shape[1:], []).append(part)
    return [GroundingSet.concat(task, group) for group in by_size.values()]


def goal_loss(pred: torch.Tensor, goals: torch.Tensor, scale) -> torch.Tensor:
    """
    Cross-entropy of the goal cell over the map's cells, the values times `scale` as logits.

    MSE alone barely penalises a peak one cell off (neighbouring true values differ by 10%), so the
    argmax often lands beside the goal, or on the object named.
    """
    b, h, w = pred.shape
    return F.cross_entropy(pred.reshape(b, h * w) * scale, goals[:, 0] * w + goals[:, 1])


def generated_validation(task: str, seed: int, per_family: int = 40) -> GroundingSet | None:
    """Fresh generated worlds (never trained on) of every family the task trains on."""
    mode = tasks.task(task).generator_mode
    if mode is None:
        return None
    return generate(per_family * len(MODES[mode]), seed=20_000 + seed, mode=mode)


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
    Train `model_name` on `task` and keep the epoch with the best validation score.

    Train `model_name` on `task`, keep the epoch with the best validation score, write
    `out/<task>_<model>.pt`; returns its path and a summary.

    Under `torchrun --nproc_per_node N` each process runs a share of every batch (distributed.py);
    only the first prints progress and writes the checkpoint.
    """
    if model_name == 't-uvfa':  # its entity table has the kinds alone: no distractor rows
        if tc.distractors:
            raise ValueError('t-UVFA has no distractor kinds; train it with --distractors 0')
        tc = replace(tc, distractors=0)
    tc = tc.for_task(task)
    if tc.synthetic and tasks.task(task).generator_mode is None:
        raise ValueError(
            f'--synthetic adds generated PuddleWorld worlds; task {task} is not PuddleWorld'
        )
    model_options = {**({} if tc.paper_model else tasks.task(task).model), **model_options}
    if tc.distractors:
        model_options['distractor_kinds'] = tc.distractors
    if model_name not in ('t-rnet-attn', 't-rnet'):  # the far relation is a relation network's
        model_options.pop('far', None)
    torch.manual_seed(tc.seed)
    torch.set_num_threads(tc.threads)
    data = train_data if train_data is not None else load_task(task, 'train', data_dir)
    train, val = split_by_world(data, tc.val_fraction, tc.seed)
    parts = training_parts(task, train, val, tc, data_dir)
    val_generated = generated_validation(task, tc.seed) if tc.synthetic else None
    # from everything trained on: generated phrasing and the mirrors' swapped direction words
    vocab = Vocabulary.build(list(data.instructions) + [t for p in parts for t in p.instructions])
    cfg = ModelConfig(
        n_entities=len(data.entities),
        vocab_size=len(vocab),
        embed_dim=data.entities.embed_dim,
        **model_options,
    )
    model = build_model(model_name, cfg)
    processes = distributed.start()
    # log of the goal logits' temperature; learned, it lets the cross-entropy ask for the right
    # argmax without pulling the values away from the MSE's (it is not part of the model)
    goal_log_scale = torch.tensor(float(np.log(tc.goal_scale)), requires_grad=tc.learn_goal_scale)
    opt = torch.optim.Adam(
        [*model.parameters()] + ([goal_log_scale] if tc.learn_goal_scale else []), lr=tc.lr
    )
    encoded, word_pools = [], []
    for part in parts:
        grids, tokens = encode(vocab, part)
        encoded.append(
            (
                grids,
                tokens,
                torch.from_numpy(part.values),
                torch.from_numpy(part.goals),
                (tokens != 0).sum(1).numpy(),
            )
        )
        word_pools.append(noise_word_pools(part, vocab) if tc.text_noise else None)
    steps_per_epoch = sum(int(np.ceil(len(p) / tc.batch_size)) for p in parts)
    warmup = int(tc.epochs * tc.attention_warmup) if getattr(model, 'attention', False) else 0
    # the model itself in one process; the warm-up leaves the attention weights unused
    trained = distributed.wrap(model, processes, find_unused=bool(warmup))
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(
        opt, T_max=(warmup or tc.epochs) * steps_per_epoch, eta_min=tc.lr_final
    )
    rng = np.random.default_rng(tc.seed)
    distractor_rng = np.random.default_rng([tc.seed, 1])  # the same draws in every process
    text_noise_rng = np.random.default_rng([tc.seed, 2])
    best = ((float('inf'),), None, -1)
    history = []
    start = time.perf_counter()
    bar = tqdm(
        range(tc.epochs),
        desc=f'{task} {model_name}',
        disable=not (progress and processes.main),
        unit='ep',
    )
    for epoch in bar:
        model.train()
        if warmup:  # uniform attention (attn weights still 0) == t-RNet, 5-10x cheaper a step
            model.attention_on = epoch >= warmup
            if epoch == warmup:  # attention starts learning: give it a full schedule of its own
                for group in opt.param_groups:
                    group['lr'] = tc.lr
                sched = torch.optim.lr_scheduler.CosineAnnealingLR(
                    opt, T_max=(tc.epochs - warmup) * steps_per_epoch, eta_min=tc.lr_final
                )
        plan = [
            (p, idx)
            for p, (*_, lengths) in enumerate(encoded)
            for idx in batches(lengths, tc.batch_size, rng)
        ]
        losses = []
        for p in rng.permutation(len(plan)):
            part, idx = plan[p]
            grids, tokens, values, goals, _ = encoded[part]
            batch = torch.from_numpy(idx)
            batch_grids = grids[batch]
            if tc.distractors:  # drawn for the whole batch: every process draws the same
                batch_grids = add_distractors(
                    model, batch_grids, goals[batch], tc.distractors, distractor_rng
                )
            batch_tokens = tokens[batch]
            if tc.text_noise:  # likewise
                batch_tokens = insert_noise_words(
                    batch_tokens, [word_pools[part][i] for i in idx], tc.text_noise, text_noise_rng
                )
            # this process's share (weight 1.0: the whole batch, alone)
            share, weight = distributed.shard(np.arange(len(idx)), processes)
            share = torch.from_numpy(share)
            idx = batch[share]
            pred = trained(batch_grids[share], _trim(batch_tokens[share]))
            loss = torch.mean((pred - values[idx]) ** 2)
            if tc.goal_weight:
                loss = loss + tc.goal_weight * goal_loss(pred, goals[idx], goal_log_scale.exp())
            opt.zero_grad()
            (loss * weight).backward()
            distributed.average_gradients([goal_log_scale], processes)
            opt.step()
            sched.step()
            losses.append(loss.item() * weight)
        losses = distributed.batch_losses(losses, processes)
        val_metrics = evaluate(model, vocab, val)
        val_hit = evaluate_hit(model, vocab, val_generated) if val_generated is not None else 0.0
        history.append((float(np.mean(losses)), val_metrics['mse'], val_metrics['pq'], val_hit))
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
            train=f'{np.mean(losses):.3f}',
            val_mse=f'{val_metrics["mse"]:.3f}',
            val_pq=f'{val_metrics["pq"]:.3f}',
            gen_hit=f'{val_hit:.3f}',
            best=best[2],
            scale=f'{goal_log_scale.exp().item():.1f}',
        )
    train_seconds = time.perf_counter() - start
    model.load_state_dict(best[1])
    val_metrics = evaluate(model, vocab, val)
    if val_generated is not None:
        val_metrics['generated_hit'] = evaluate_hit(model, vocab, val_generated)
    n_train = sum(len(p) for p in parts)
    summary = {
        'task': task,
        'train_examples': n_train,
        'val_examples': len(val),
        'best_epoch': best[2],
        'epochs': tc.epochs,
        'train_seconds': round(train_seconds, 1),
        'val': val_metrics,
        'train_config': vars(tc).copy(),
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
            goal_scale=round(float(goal_log_scale.detach().exp()), 3),
            train_seconds=summary['train_seconds'],
            train_config=vars(tc).copy(),
            loss_history=[[round(x, 5) for x in row] for row in history],
            **({'processes': processes.size} if processes.size > 1 else {}),
        )
    distributed.finish(processes)
    return path, summary
