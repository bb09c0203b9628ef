# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
ShapeWorld training, evaluation and checkpoints; commands.py makes the subcommands of them.

Adam at the paper's learning rate with a cosine decay, cross-entropy (the softmax of the paper's
classification loss), a validation split carved out of train selects the epoch; the test split
is only ever evaluated. Training mirrors a random half of each batch left to right, swapping
"left" and "right" in its statements: every shape is left-right symmetric, so a mirrored example
is another correctly labelled one.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path
import time

import numpy as np
import torch
import torch.nn.functional as F
from tqdm import tqdm

from .data import (
    ABSENT,
    converse,
    image_noise,
    load_split,
    REASONS,
    scene_attributes,
    ShapeWorldSet,
    text_noise,
)
from .models import build_model, MODELS, ShapeWorldConfig
from ..core.text import Vocabulary
from ..models.checkpoints import read_checkpoint, SHAPEWORLD, write_checkpoint
from ..training.options import check, option

TASK = SHAPEWORLD  # the checkpoints' task, which tells them from the grid models'
# epochs over the training split after the curriculum's warm-up (TrainConfig), per model: on
# the mixed false statements t-RNetAttn's validation accuracy still rose after ten; t-VGG,
# with its scene loss, reaches it in about half the steps (docs/shapeworld.md)
EPOCHS = {'t-rnet-attn': 20, 't-vgg': 10}
SWAP_LEFT_RIGHT = {'left': 'right', 'right': 'left'}
WARMUP_SEED = 2  # the warm-up set is drawn apart from the training split (seed 0)


@dataclass
class TrainConfig:
    """
    Training hyper-parameters, each declared once: `shapeworld-train` makes its options of them.

    Batch 32, more updates an epoch than a larger batch: the task has a long plateau at chance.
    The training split is larger than the paper's 9000 (its test split stays 500): on plausible
    false statements nothing short of the whole relation predicts a label, and 9000 were
    memorised first. The curriculum's warm-up comes first: statements (a separate generated
    set) whose false ones all name, on one side, an object the image lacks, so that checking
    which objects exist, the names' grounding, predicts labels; training on plausible false
    statements from the start sat at chance.
    """

    epochs: int | None = option(
        None, "epochs over the training split after the warm-up (default: the model's)", low=1
    )
    batch_size: int = option(32, 'examples per optimizer step', low=1)
    lr: float = option(1e-3, "Adam learning rate at the start (the paper's)", low=0.0)
    lr_final: float = option(1e-4, 'learning rate at the end of the cosine decay', low=0.0)
    val_fraction: float = option(
        0.1, 'share of the training split held out for validation', low=0.01, high=0.9
    )
    mirror: bool = option(True, 'mirror a random half of each batch left to right')
    converse: bool = option(True, 'state a random half of the statements the other way round')
    train_size: int | None = option(
        60000, "generated training statements (None: the paper's 9000)", low=1
    )
    absent: float = option(
        ABSENT,
        "share of the training split's false statements that name an absent object (the "
        "splits' mix; 0: all plausible, the previous data)",
        low=0.0, high=1.0,
    )
    warmup_size: int = option(20000, 'generated warm-up statements (0: no warm-up)', low=0)
    warmup_epochs: int = option(3, 'epochs over the warm-up set (0: no warm-up)', low=0)
    warmup_absent: float = option(
        1.0, "share of the warm-up's false statements that name an absent object",
        low=0.0, high=1.0,
    )
    scene_weight: float = option(
        20.0,
        "weight of t-VGG's scene loss (the mean binary cross-entropy over which of 8 shapes, 8 "
        'colours and 64 pairs the image holds, read from its image representation; 0: none; '
        't-RNetAttn has no such head)',
        low=0.0,
    )
    seed: int = option(0, 'seed of the weights, the split and the batches', low=0, high=2**32 - 1)
    threads: int = option(1, 'torch threads', low=1)
    max_minutes: float | None = option(
        28.0,
        "the issue's budget: training stops after this many minutes, the epoch under way ends "
        'there and is validated like the others (0 or None: no limit)',
        low=0.0,
    )

    def __post_init__(self):
        check(self)


def encode(vocab: Vocabulary, statements: list[str]) -> torch.Tensor:
    return torch.from_numpy(vocab.encode_batch(statements))


def as_input(images: np.ndarray) -> torch.Tensor:
    """(N,64,64,3) uint8 or float in [0, 1] -> (N,3,64,64) float."""
    x = torch.from_numpy(images).permute(0, 3, 1, 2).float()
    return x / 255 if images.dtype == np.uint8 else x


@torch.no_grad()
def predict(model, vocab: Vocabulary, images: np.ndarray, statements: list[str], batch=256):
    """P(true) per example."""
    model.eval()
    out = []
    for i in range(0, len(statements), batch):
        logits = model(as_input(images[i:i + batch]), encode(vocab, statements[i:i + batch]))
        out.append(logits.softmax(-1)[:, 1])
    return torch.cat(out).numpy()


def accuracy(model, vocab: Vocabulary, data: ShapeWorldSet, image_k=0, text_k=0, seed=0) -> dict:
    """
    Accuracy, with k noise patches in each image and k words inserted in each statement.

    `acc` and `n` over all, and `by_reason`: the same over the true statements and over the
    false ones of each reason (data.REASONS) that the set holds.
    """
    rng = np.random.default_rng(seed)
    images = image_noise(data.images, data.objects, image_k, rng) if image_k else data.images
    statements = text_noise(data.statements, text_k, rng) if text_k else data.statements
    correct = (predict(model, vocab, images, statements) > 0.5) == (data.labels == 1)
    reasons = np.array(data.reasons)
    by_reason = {
        r: {'acc': float(correct[reasons == r].mean()), 'n': int((reasons == r).sum())}
        for r in REASONS if (reasons == r).any()
    }
    return {'acc': float(correct.mean()), 'n': len(data), 'by_reason': by_reason}


def save(path: Path, name: str, model, cfg: ShapeWorldConfig, vocab: Vocabulary, **info) -> Path:
    """Write a ShapeWorld checkpoint: the package's format (checkpoints.py), task 'shapeworld'."""
    return write_checkpoint(path, name, model, cfg.to_dict(), vocab, task=TASK, **info)


def load(name: str | Path):
    """
    Return (model, vocabulary, header) of a ShapeWorld checkpoint, a path or a packaged name.

    A grid model's checkpoint, or weights that do not fit the model the header names, is one
    ValueError line.
    """
    path, header, state = read_checkpoint(name, TASK)
    vocab = Vocabulary(header['vocabulary'][2:])
    try:
        cfg = ShapeWorldConfig.from_dict(header['config'])
        model = build_model(header['model'], cfg)
        model.load_state_dict(state)
    except (TypeError, ValueError, RuntimeError) as exc:
        first = str(exc).splitlines()[0]
        raise ValueError(f'{path}: does not fit the ShapeWorld model: {first}') from exc
    if cfg.vocab_size != len(vocab):
        raise ValueError(f'{path}: vocabulary {len(vocab)} words, config {cfg.vocab_size}')
    model.eval()
    return model, vocab, header


class Batches:
    """
    One stage's training examples and their augmentations, in batches.

    Images stay uint8 until a batch is made (float, all 60000 would take 3 GB). A random half
    of each batch is mirrored left to right with "left" and "right" swapped (every shape is
    left-right symmetric), and a random half of the statements is said the other way round
    ("Y is right of X" for "X is left of Y": the same claim).
    """

    def __init__(self, data: ShapeWorldSet, vocab: Vocabulary):
        """Encode the statements and their converses once."""
        self.images = torch.from_numpy(data.images)
        tokens = encode(vocab, data.statements)
        self.conversed = encode(vocab, [converse(s) for s in data.statements])
        self.tokens = F.pad(tokens, (0, self.conversed.shape[1] - tokens.shape[1]))
        self.labels = torch.from_numpy(data.labels)
        self.scenes = torch.from_numpy(scene_attributes(data.objects))
        self.swap = torch.tensor(
            [vocab.index.get(SWAP_LEFT_RIGHT.get(w, w), i) for i, w in enumerate(vocab.words)]
        )

    def __len__(self) -> int:
        """Return the number of examples."""
        return len(self.labels)

    def __call__(self, rng: np.random.Generator, tc: 'TrainConfig'):
        """Yield one epoch of (images, tokens, labels, scene attributes) batches, shuffled."""
        for idx in torch.from_numpy(rng.permutation(len(self))).split(tc.batch_size):
            x = self.images[idx].permute(0, 3, 1, 2).float() / 255
            t, y = self.tokens[idx], self.labels[idx]
            if tc.converse:
                other = torch.from_numpy(rng.random(len(idx)) < 0.5)
                t = torch.where(other[:, None], self.conversed[idx], t)
            if tc.mirror:  # a random half of the batch, at no extra cost a step
                flip = torch.from_numpy(rng.random(len(idx)) < 0.5)
                t = t.clone()
                x[flip], t[flip] = x[flip].flip(-1), self.swap[t[flip]]
            yield x, t, y, self.scenes[idx]


def train(
    model_name: str,
    out: str | Path,
    tc: TrainConfig = TrainConfig(),
    cache_dir: str | Path | None = None,
    progress: bool = True,
    **model_options,
) -> tuple[Path, dict]:
    """Train on ShapeWorld train, keep the epoch of best validation accuracy, write the .pt."""
    if model_name not in MODELS:
        raise ValueError(f'ShapeWorld has no model {model_name!r}; use one of {", ".join(MODELS)}')
    epochs = tc.epochs if tc.epochs is not None else EPOCHS[model_name]  # TrainConfig checks
    torch.manual_seed(tc.seed)
    torch.set_num_threads(tc.threads)
    data = load_split('train', cache_dir, n=tc.train_size, absent=tc.absent)
    rng = np.random.default_rng(tc.seed)
    order = rng.permutation(len(data))
    n_val = max(1, int(len(data) * tc.val_fraction))
    train_set, val = data.subset(order[n_val:]), data.subset(order[:n_val])
    vocab = Vocabulary.build(data.statements)
    cfg = ShapeWorldConfig(vocab_size=len(vocab), **model_options)
    model = build_model(model_name, cfg)
    scene_head = tc.scene_weight > 0 and hasattr(model, 'scene')
    # the curriculum: statements with absent objects first, then the whole task (TrainConfig)
    stages = [(train_set, epochs)]
    if tc.warmup_epochs and tc.warmup_size:
        warmup = load_split(
            'train', cache_dir, tc.warmup_size, WARMUP_SEED, absent=tc.warmup_absent
        )
        stages.insert(0, (warmup, tc.warmup_epochs))
    schedule = [(batches, e) for batches, e in ((Batches(d, vocab), e) for d, e in stages)]
    opt = torch.optim.Adam(model.parameters(), lr=tc.lr)
    steps = sum(e * int(np.ceil(len(b) / tc.batch_size)) for b, e in schedule)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, T_max=steps, eta_min=tc.lr_final)
    best = (-1.0, None, -1)
    history = []
    start = time.perf_counter()
    epoch_sets = [b for b, e in schedule for _ in range(e)]
    bar = tqdm(epoch_sets, desc=f'{TASK} {model_name}', disable=not progress, unit='ep')
    out_of_time = False
    for epoch, batches in enumerate(bar):
        model.train()
        losses = []
        for x, t, y, scene in batches(rng, tc):
            if tc.max_minutes and time.perf_counter() - start > 60 * tc.max_minutes:
                out_of_time = True
                break
            if scene_head:
                logits, aux = model(x, t, return_aux=True)
                loss = F.cross_entropy(logits, y)
                loss = loss + tc.scene_weight * F.binary_cross_entropy_with_logits(
                    aux['scene'], scene
                )
            else:
                loss = F.cross_entropy(model(x, t), y)
            opt.zero_grad()
            loss.backward()
            opt.step()
            sched.step()
            losses.append(loss.item())
        if not losses:  # out of time at the start of an epoch
            break
        val_acc = accuracy(model, vocab, val)['acc']
        history.append((float(np.mean(losses)), val_acc))
        if val_acc > best[0]:
            best = (val_acc, {k: v.clone() for k, v in model.state_dict().items()}, epoch)
        bar.set_postfix(loss=f'{np.mean(losses):.3f}', val_acc=f'{val_acc:.3f}', best=best[2])
        if out_of_time:
            break
    train_seconds = time.perf_counter() - start
    model.load_state_dict(best[1])
    summary = {
        'task': TASK,
        'model': model_name,
        'train_examples': len(train_set),
        'val_examples': len(val),
        'epochs': len(history),
        'stopped_at_time_limit': out_of_time,
        'best_epoch': best[2],
        'val_acc': best[0],
        'train_seconds': round(train_seconds, 1),
        'train_config': {**asdict(tc), 'epochs': epochs},
        'train_steps': steps,
    }
    path = save(
        Path(out) / f'{TASK}_{model_name}.pt',
        model_name,
        model,
        cfg,
        vocab,
        training_data=f'ShapeWorld generated ({len(train_set)} train / {len(val)} validation)',
        **{k: v for k, v in summary.items() if k not in ('task', 'model')},
        loss_history=[[round(x, 5) for x in row] for row in history],
    )
    return path, summary
