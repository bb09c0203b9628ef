# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
`make reproduce-shapeworld`: train both classifiers, ship them, and write the results tables.

results/shapeworld.json holds every figure; shapeworld.md sets the test accuracy beside the
paper's Table 1, with the accuracy on each reason of a label (true; false by the relation, by an
absent subject, by an absent reference) and on the all-plausible test split of the previous
data version (every false statement false by its relation, data.generate(absent=0)), and
shapeworld_noise.md the accuracy under image and text noise at the paper's k.
"""

from __future__ import annotations

import json
from pathlib import Path
import platform

import torch

from .data import load_split, REASONS
from .training import accuracy, EPOCHS, load, TASK, train, TrainConfig
from ..models.checkpoints import PACKAGED_DIR

REPRODUCED = ('t-vgg', 't-rnet-attn')  # table order: baseline first
PAPER_ACC = {'t-vgg': 0.71, 't-rnet-attn': 0.72}  # the paper's Table 1
NOISE_KS = (0, 1, 2, 5, 10)  # the noise study's k, as the paper's figures
# the results table's column of each reason of a label (data.REASONS)
REASON_COLUMNS = {
    'true': 'true',
    'relation': 'false: relation',
    'subject': 'false: no subject',
    'reference': 'false: no reference',
}


def markdown_tables(rows: list[dict], noise: list[dict]) -> tuple[str, str]:
    """Return results/shapeworld.md (accuracy beside the paper's) and shapeworld_noise.md."""
    main = [
        'ShapeWorld true-or-false statements, test split; paper = Yang et al. 2020 Table 1; '
        'then the accuracy on the test statements that are true and on the false ones by '
        'their reason (n each), and on the all-plausible test split (every false statement '
        'false by its relation, the previous data).',
        '',
        '| model | ACC ours | ACC paper | n | '
        + ' | '.join(f'{REASON_COLUMNS[reason]} (n)' for reason in REASONS)
        + ' | all-plausible test | epochs | train min |',
        '| --- | --- | --- | --- |' + ' --- |' * len(REASONS) + ' --- | --- | --- |',
    ]
    for r in rows:
        by = r['test']['by_reason']
        main.append(
            f'| {r["model"]} | {r["test"]["acc"]:.3f} | {PAPER_ACC[r["model"]]:.2f} '
            f'| {r["test"]["n"]} | '
            + ' | '.join(f'{by[k]["acc"]:.3f} ({by[k]["n"]})' for k in REASONS)
            + f' | {r["test_plausible"]["acc"]:.3f} | {r["epochs"]} '
            f'| {r["train_seconds"] / 60:.1f} |'
        )
    models = [r['model'] for r in rows]
    table = {(e['noise'], e['k'], e['model']): e['acc'] for e in noise}
    lines = [
        'ShapeWorld test accuracy under noise (`spatial-grounding shapeworld-eval '
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


def evaluate_shipped(name: str, test, plausible) -> tuple[dict, list[dict]]:
    """Return the shipped checkpoint's results row and its noise rows, one per noise and k."""
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
        'test_plausible': accuracy(model, vocab, plausible),
    }
    print(f'{TASK} {name}: test {row["test"]}', flush=True)
    noise = []
    for kind in ('image', 'text'):
        for k in NOISE_KS:
            ks = (k, 0) if kind == 'image' else (0, k)
            acc = accuracy(model, vocab, test, *ks)
            noise.append({'model': name, 'noise': kind, 'k': k, 'acc': acc['acc'], 'n': acc['n']})
    return row, noise


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
    out = Path(out)
    test = load_split('test', cache_dir)
    plausible = load_split('test', cache_dir, absent=0.0)
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
        row, noisy = evaluate_shipped(name, test, plausible)
        rows.append(row)
        noise += noisy
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
