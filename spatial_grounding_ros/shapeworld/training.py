# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
ShapeWorld training, evaluation, checkpoints, commands and the reproduction, top to bottom.

Adam at the paper's learning rate with a cosine decay, cross-entropy (the softmax of the paper's
classification loss), a validation split carved out of train selects the epoch; the test split
is only ever evaluated. Training mirrors a random half of each batch left to right, swapping
"left" and "right" in its statements: every shape is left-right symmetric, so a mirrored example
is another correctly labelled one.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
import json
from pathlib import Path
import platform
import time

import numpy as np
import torch
import torch.nn.functional as F
from tqdm import tqdm

from .data import converse, image_noise, load_split, ShapeWorldSet, text_noise
from .models import build_model, MODELS, ShapeWorldConfig
from ..core.text import Vocabulary
from ..models.checkpoints import read_checkpoint, SHAPEWORLD, write_checkpoint

TASK = SHAPEWORLD  # the checkpoints' task, which tells them from the grid models'
# epochs over the training split after the curriculum's warm-up (TrainConfig), per model
EPOCHS = {'t-rnet-attn': 3, 't-vgg': 3}
PAPER_ACC = {'t-vgg': 0.71, 't-rnet-attn': 0.72}  # the paper's Table 1
NOISE_KS = (0, 1, 2, 5, 10)  # the noise study's k, as the paper's figures
SWAP_LEFT_RIGHT = {'left': 'right', 'right': 'left'}
WARMUP_SEED = 2  # the warm-up set is drawn apart from the training split (seed 0)


@dataclass
class TrainConfig:
    """Training hyper-parameters (epochs None: the model's EPOCHS)."""

    epochs: int | None = None
    batch_size: int = 32  # more updates an epoch: the task has a long plateau at chance
    lr: float = 1e-3  # the paper's
    lr_final: float = 1e-4  # cosine decay to this
    val_fraction: float = 0.1  # of the training split
    mirror: bool = True  # mirror a random half of each batch left-right
    converse: bool = True  # state a random half of the statements the other way round
    # More than the paper's 9000 (its test split stays 500): with plausible false statements
    # nothing short of the whole relation predicts a label, and 9000 are memorised first.
    train_size: int | None = 60000
    # Curriculum: first these epochs over this many statements (a separate generated set)
    # whose false ones name, on one side, an object the image lacks (a fraction
    # `warmup_absent` of them): checking which objects exist, the names' grounding, then
    # predicts labels. On plausible false statements only the whole relation does, and training
    # from the start sat at chance.
    warmup_size: int = 20000
    warmup_epochs: int = 3
    warmup_absent: float = 1.0
    seed: int = 0
    threads: int = 1
    # the budget: training stops after this many minutes (the epoch under way ends
    # there and is validated like the others); None: no limit
    max_minutes: float | None = 28.0


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
    """Test accuracy, with k noise patches in each image and k words inserted in each statement."""
    rng = np.random.default_rng(seed)
    images = image_noise(data.images, data.objects, image_k, rng) if image_k else data.images
    statements = text_noise(data.statements, text_k, rng) if text_k else data.statements
    correct = (predict(model, vocab, images, statements) > 0.5) == (data.labels == 1)
    return {'acc': float(correct.mean()), 'n': len(data)}


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
        self.swap = torch.tensor(
            [vocab.index.get(SWAP_LEFT_RIGHT.get(w, w), i) for i, w in enumerate(vocab.words)]
        )

    def __len__(self) -> int:
        """Return the number of examples."""
        return len(self.labels)

    def __call__(self, rng: np.random.Generator, tc: 'TrainConfig'):
        """Yield one epoch of (images, tokens, labels) batches in a random order."""
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
            yield x, t, y


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
    epochs = tc.epochs if tc.epochs is not None else EPOCHS[model_name]
    if epochs < 1 or tc.batch_size < 1:
        raise ValueError(f'epochs and batch size must be positive, got {epochs}, {tc.batch_size}')
    torch.manual_seed(tc.seed)
    torch.set_num_threads(tc.threads)
    data = load_split('train', cache_dir, n=tc.train_size)
    rng = np.random.default_rng(tc.seed)
    order = rng.permutation(len(data))
    n_val = max(1, int(len(data) * tc.val_fraction))
    train_set, val = data.subset(order[n_val:]), data.subset(order[:n_val])
    vocab = Vocabulary.build(data.statements)
    cfg = ShapeWorldConfig(vocab_size=len(vocab), **model_options)
    model = build_model(model_name, cfg)
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
        for x, t, y in batches(rng, tc):
            if tc.max_minutes is not None and time.perf_counter() - start > 60 * tc.max_minutes:
                out_of_time = True
                break
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


# --- commands -----------------------------------------------------------------------------

def add_cli_options(train_parser, eval_parser) -> None:
    """Add the options of --task shapeworld (the noise options: noise.add_noise_options)."""
    for p in (train_parser, eval_parser):
        p.add_argument(
            '--cache',
            default=None,
            help='ShapeWorld: folder of the generated splits (default: $SPATIAL_GROUNDING_CACHE '
            'or ~/.cache/spatial_grounding_ros)',
        )
    eval_parser.add_argument(
        '--image-noise',
        type=int,
        default=0,
        metavar='K',
        help='ShapeWorld: K patches of N(0, 1) pixels in each image, clear of the objects',
    )


def cmd_train(args, given: dict) -> int:
    """`train --task shapeworld`: `given` holds the train options given (the grid tasks')."""
    ours = {f.name for f in fields(TrainConfig)}
    other = [name for name in given if name not in ours]
    if other:
        options = ', '.join('--' + name.replace('_', '-') for name in other)
        raise ValueError(f'{options}: not an option of --task {TASK}')
    path, summary = train(args.model, args.out, TrainConfig(**given), args.cache)
    print(json.dumps({'checkpoint': str(path), **summary}, indent=2))
    return 0


def cmd_eval(args) -> int:
    if args.task != TASK:
        raise ValueError(f'--image-noise is an option of --task {TASK}')
    if args.obs_noise or args.unknown_words:
        raise ValueError(f'--task {TASK} takes --image-noise and --text-noise, not --obs-noise '
                         'or --unknown-words')
    if args.image_noise < 0 or args.text_noise < 0:
        raise ValueError('--image-noise and --text-noise count patches and words: 0 or more')
    model, vocab, header = load(args.checkpoint)
    result = {
        'checkpoint': str(args.checkpoint),
        'model': header['model'],
        'task': TASK,
        'split': args.split,
        'image_noise': args.image_noise,
        'text_noise': args.text_noise,
        'seed': args.seed,
        **accuracy(
            model,
            vocab,
            load_split(args.split, args.cache),
            args.image_noise,
            args.text_noise,
            args.seed,
        ),
    }
    if args.json:
        print(json.dumps(result))
    else:
        print(f'{header["model"]} on {TASK} {args.split} (n={result["n"]}): '
              f'ACC {result["acc"]:.3f}')
    return 0


# --- `make reproduce-shapeworld` ----------------------------------------------------------

REPRODUCED = ('t-vgg', 't-rnet-attn')  # table order: baseline first


def markdown_tables(rows: list[dict], noise: list[dict]) -> tuple[str, str]:
    """results/shapeworld.md (accuracy beside the paper's) and shapeworld_noise.md."""
    main = [
        'ShapeWorld true-or-false statements, test split; paper = Yang et al. 2020 Table 1.',
        '',
        '| model | ACC ours | ACC paper | n | epochs | train min |',
        '| --- | --- | --- | --- | --- | --- |',
    ]
    for r in rows:
        main.append(
            f'| {r["model"]} | {r["test"]["acc"]:.3f} | {PAPER_ACC[r["model"]]:.2f} '
            f'| {r["test"]["n"]} | {r["epochs"]} | {r["train_seconds"] / 60:.1f} |'
        )
    models = [r['model'] for r in rows]
    table = {(e['noise'], e['k'], e['model']): e['acc'] for e in noise}
    lines = [
        'ShapeWorld test accuracy under noise (`spatial-grounding eval --task shapeworld '
        '--image-noise K` / `--text-noise K`, seed 0).',
        '',
        '| noise | k | ' + ' | '.join(f'{m} ACC' for m in models) + ' |',
        '| --- | --- |' + ' --- |' * len(models),
    ]
    for kind in ('image', 'text'):
        for k in NOISE_KS:
            accs = ' | '.join(f'{table[kind, k, m]:.3f}' for m in models)
            lines.append(f'| {kind} | {k} | {accs} |')
    return '\n'.join(main) + '\n', '\n'.join(lines) + '\n'


def reproduce(
    out: str | Path,
    models=REPRODUCED,
    threads: int = 1,
    epochs_scale: float = 1.0,
    eval_only: bool = False,
    cache_dir: str | Path | None = None,
) -> dict:
    """
    Train the models one after the other, ship their checkpoints, evaluate them clean and noisy.

    `eval_only` skips training and evaluates the shipped checkpoints (the tables of a given
    set of checkpoints, e.g. after the noise study changed).
    """
    from ..models.checkpoints import PACKAGED_DIR

    out = Path(out)
    test = load_split('test', cache_dir)
    if not eval_only:
        # one model after the other, one process of `threads` threads: on a shared 2-core
        # machine two at once would each get less than a core
        # the model the minimum is about first
        for name in sorted(models, key=lambda name: name != 't-rnet-attn'):
            tc = TrainConfig(epochs=max(1, round(EPOCHS[name] * epochs_scale)), threads=threads)
            path, summary = train(name, out / 'checkpoints', tc, cache_dir)
            print(f'{TASK} {name}: {summary}', flush=True)
            (PACKAGED_DIR / path.name).write_bytes(path.read_bytes())
    rows, noise = [], []
    for name in models:
        packaged = PACKAGED_DIR / f'{TASK}_{name}.pt'
        model, vocab, header = load(packaged)
        row = {
            'model': name,
            'checkpoint': packaged.name,
            'epochs': header['epochs'],
            'best_epoch': header['best_epoch'],
            'val_acc': header['val_acc'],
            'train_seconds': header['train_seconds'],
            'test': accuracy(model, vocab, test),
        }
        print(f'{TASK} {name}: test {row["test"]}', flush=True)
        rows.append(row)
        for kind in ('image', 'text'):
            for k in NOISE_KS:
                ks = (k, 0) if kind == 'image' else (0, k)
                noise.append(
                    {'model': name, 'noise': kind, 'k': k, **accuracy(model, vocab, test, *ks)}
                )
    command = 'spatial-grounding reproduce-shapeworld' + (' --eval-only' if eval_only else '')
    meta = {
        'command': command,
        'machine': platform.processor() or platform.machine(),
        'torch': torch.__version__,
        'threads': threads,
    }
    results = {'meta': meta, 'runs': rows, 'noise': noise}
    out.mkdir(parents=True, exist_ok=True)
    (out / 'shapeworld.json').write_text(json.dumps(results, indent=1) + '\n')
    main, noise_md = markdown_tables(rows, noise)
    (out / 'shapeworld.md').write_text(main)
    (out / 'shapeworld_noise.md').write_text(noise_md)
    return results


def cmd_reproduce(args) -> int:
    reproduce(args.out, args.models, args.threads, args.epochs_scale, args.eval_only, args.cache)
    return 0


def register_cli(sub) -> None:
    r = sub.add_parser(
        'reproduce-shapeworld',
        help='train and evaluate t-VGG and t-RNetAttn on ShapeWorld, ship the checkpoints, '
        'write results/shapeworld.{json,md} and the noise table',
    )
    r.add_argument('--out', default='results')
    r.add_argument('--models', nargs='+', default=list(REPRODUCED), choices=list(MODELS))
    r.add_argument('--threads', type=int, default=1, help='torch threads per training run')
    r.add_argument(
        '--epochs-scale', type=float, default=1.0, help='multiply each epoch budget (quick check)'
    )
    r.add_argument(
        '--eval-only', action='store_true', help='evaluate the shipped checkpoints, no training'
    )
    r.add_argument('--cache', default=None, help='folder of the generated splits')
    r.set_defaults(func=cmd_reproduce)
