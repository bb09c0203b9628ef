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

from dataclasses import dataclass, fields, replace
from pathlib import Path
import time

import numpy as np
import torch
from tqdm import tqdm

from . import distributed
from .epochs import Epochs, trim_padding
from .options import check, option
from ..core import tasks, world
from ..core.text import Vocabulary
from ..data.augment import NOISE_SHARE, with_mirrors
from ..data.datasets import (
    GroundingSet,
    load_task,
    load_world_instructions,
    pw_world_ids,
    split_by_world,
)
from ..data.generator import generate, MODES
from ..data.noise import kind_word_ids, MAX_K
from ..data.paraphrase import paraphrased
from ..models.checkpoints import load_checkpoint, save_checkpoint
from ..models.config import ModelConfig
from ..models.protocol import Capabilities
from ..models.registry import build_model, capabilities
from ..models.trnet import TRNet

# (map size, share of the generated examples): most at Janner's 10x10, some larger so that
# references that span the map (extremes, gradients) learn how they scale.
SYNTHETIC_SIZES = ((10, 0.75), (16, 0.17), (24, 0.08))
# share of epochs before a run's --late-row-col worlds join, by default
LATE_FROM = 0.75


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
    generator_mode: str | None = option(
        None,
        "the generated worlds' mix of families, training and validation (data/generator.py "
        "MODES; default: the task's)",
        choices=tuple(MODES),
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
        'up to this many noise words (unknown words, verbs, articles) at one position of half '
        "the training instructions, once the attention trains (0: none; default: the task's)",
        low=0,
        high=MAX_K,  # as many as the robustness study inserts
    )
    noise_names: bool | None = option(
        None,
        'the noise words also name kinds neither on the map nor in the instruction (a third of '
        "them), as the robustness study's text-noise does: the node's Grounder leaves such "
        "names out, the network alone reads them (default: the task's recipe's, or off)",
    )
    skip_unknown: bool | None = option(
        None,
        'the model reads past words outside its vocabulary (ModelConfig.skip_unknown), and the '
        "noise words are fillers and names alone (default: the task's recipe's, or off)",
    )
    skip_absent_names: bool | None = option(
        None,
        'once trained, the model reads a name of a kind its map lacks as an unknown word, past '
        'which --skip-unknown reads (ModelConfig.name_words): that landmark cannot be the one '
        "meant. Training reads its instructions as written (default: the task's recipe's, or "
        'off)',
    )
    noise_share: float | None = option(
        None,
        f'share of the training instructions that get noise words (default: {NOISE_SHARE})',
        low=0.0,
        high=1.0,
    )
    late_row_col: int | None = option(
        None,
        'generated row-col worlds added to training for its last epochs only (from '
        '--late-from): row-col in the whole run cost the human global split (docs/landmarks.md) '
        "(default: the task's recipe's, or none)",
        low=0,
    )
    late_from: float | None = option(
        None,
        f'share of epochs before the --late-row-col worlds join (default: {LATE_FROM})',
        low=0.0,
        high=1.0,
    )
    paraphrase: float | None = option(
        None,
        'share of the generated training instructions reworded as people word them '
        "(data/paraphrase.py; 0: none; default: the task's)",
        low=0.0,
        high=1.0,
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
    init: str | None = option(
        None,
        "start from this checkpoint's weights (a packaged name or a path; its config and "
        'vocabulary must be the ones this run builds): fine-tuning',
    )
    seed: int = option(0, 'seed of the weights, the split and the batches', low=0, high=2**32 - 1)
    threads: int = option(2, 'torch threads', low=1)

    def __post_init__(self):
        check(self)

    def for_task(self, task: str, model: str) -> 'TrainConfig':
        """Return this config with every field left at None set to `model`'s value on `task`."""
        settings = tasks.task(task)
        own = settings.recipes.get(model, {})  # the model's fields over the task's
        return replace(
            self,
            **{
                f.name: own[f.name] if f.name in own else getattr(settings, f.name)
                for f in fields(self)
                if getattr(self, f.name) is None and (f.name in own or hasattr(settings, f.name))
            },
        )


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
    task: tasks.Task, train: GroundingSet, val: GroundingSet, tc: TrainConfig, data_dir: str | Path
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
    for n, size, count in per_size(tc.synthetic or 0):
        seed = 10_000 + 100 * tc.seed + n
        generated = generate(count, seed=seed, mode=tc.generator_mode, size=size)
        parts.append(paraphrased(generated, tc.paraphrase or 0.0, seed))
    # one set per map size, so that a batch holds maps of one size
    by_size: dict[tuple, list[GroundingSet]] = {}
    for part in parts:
        by_size.setdefault(part.grids.shape[1:], []).append(part)
    return [GroundingSet.concat(task.name, group) for group in by_size.values()]


def per_size(total: int) -> list[tuple[int, int, int]]:
    """Split `total` generated worlds over SYNTHETIC_SIZES: (index, map size, count > 0)."""
    counts = [
        (n, size, int(round(total * share))) for n, (size, share) in enumerate(SYNTHETIC_SIZES)
    ]
    return [(n, size, count) for n, size, count in counts if count]


def late_parts(tc: TrainConfig) -> list[GroundingSet]:
    """Return the generated row-col worlds of `tc.late_row_col`, one set per map size."""
    return [
        generate(count, seed=30_000 + 100 * tc.seed + n, mode='training', size=size,
                 families=('row-col',))
        for n, size, count in per_size(tc.late_row_col or 0)
    ]


def generated_validation(
    mode: str | None, seed: int, per_family: int = 40
) -> GroundingSet | None:
    """Fresh generated worlds (never trained on) of every family of generator mode `mode`."""
    if mode is None:
        return None
    return generate(per_family * len(MODES[mode]), seed=20_000 + seed, mode=mode)


def task_training_config(
    task: tasks.Task, model_name: str, supports: Capabilities, tc: TrainConfig
) -> TrainConfig:
    """
    Return `tc` completed with the task's values for a model that `supports` so much.

    A model without distractor rows trains without the task's distractors, and refuses them
    when they are asked for.
    """
    if not supports.distractor_rows:  # its entity table has the kinds alone
        if tc.distractors:
            raise ValueError(
                f'{model_name} has no distractor kinds; train it with --distractors 0'
            )
        tc = replace(tc, distractors=0)
    tc = tc.for_task(task.name, model_name)
    # a mode given to a task without one (ISI) would generate PuddleWorld worlds for it
    if task.generator_mode is None and (tc.synthetic or tc.generator_mode or tc.late_row_col):
        raise ValueError(
            '--synthetic, --generator-mode and --late-row-col add generated PuddleWorld '
            f'worlds; task {task.name} is not PuddleWorld'
        )
    return tc


def model_config(
    task: tasks.Task,
    supports: Capabilities,
    tc: TrainConfig,
    data: GroundingSet,
    vocab: Vocabulary,
    model_options: dict,
) -> ModelConfig:
    """Return the config of the model trained: the task's model options, as far as it supports."""
    model_options = {**({} if tc.paper_model else task.model), **model_options}
    if tc.distractors:
        model_options['distractor_kinds'] = tc.distractors
    if tc.skip_unknown:
        model_options['skip_unknown'] = True
    if not supports.far_relation:  # the far relation is a relation network's
        model_options.pop('far', None)
    return ModelConfig(
        n_entities=len(data.entities),
        vocab_size=len(vocab),
        embed_dim=data.entities.embed_dim,
        **model_options,
    )


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
    settings, supports = tasks.task(task), capabilities(model_name)
    tc = task_training_config(settings, model_name, supports, tc)
    torch.manual_seed(tc.seed)
    torch.set_num_threads(tc.threads)
    data = train_data if train_data is not None else load_task(task, 'train', data_dir)
    train, val = split_by_world(data, tc.val_fraction, tc.seed)
    parts = training_parts(settings, train, val, tc, data_dir)
    late = late_parts(tc)  # trained on from epoch late_from * epochs on only
    val_generated = generated_validation(tc.generator_mode, tc.seed) if tc.synthetic else None
    # from everything trained on: generated phrasing and the mirrors' swapped direction words
    vocab = Vocabulary.build(
        list(data.instructions) + [t for p in parts + late for t in p.instructions]
    )
    cfg = model_config(settings, supports, tc, data, vocab, model_options)
    model = build_model(model_name, cfg)
    if tc.skip_absent_names and not isinstance(model, TRNet):
        raise ValueError(f'--skip-absent-names: {model_name} does not read it (t-RNet models do)')
    if tc.init:
        start_from(model, cfg, vocab, tc.init)
    processes = distributed.start()
    late_from = LATE_FROM if tc.late_from is None else tc.late_from
    epochs = Epochs(
        model, parts + late, vocab, tc, processes, (len(parts), int(tc.epochs * late_from))
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
