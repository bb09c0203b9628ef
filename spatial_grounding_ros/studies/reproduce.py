# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
`make reproduce`.

Train every model on every task, evaluate on the test splits, write `results/value_map.json` and
`results/value_map.md` (the README table), and ship the t-RNetAttn, t-RNet and t-CNN checkpoints
in the package, the default calibrated as the node uses it. `make reproduce-suite` (`--suite-only`)
runs the reference suite on the shipped PuddleWorld checkpoints (`results/suite.*`,
`results/landmarks.*`).
"""

from __future__ import annotations

import json
from pathlib import Path
import platform
import shutil
import time

import numpy as np
import torch
from tqdm import tqdm

from .results import code_version, merge_rows
from ..core.tasks import RL_TASKS, TASKS
from ..data.datasets import load_task
from ..data.renaming import NAMINGS
from ..models.checkpoints import load_checkpoint, PACKAGED_DIR
from ..training.recipe import recipe, TrainConfig
from ..training.rl import RLConfig, train_rl
from ..training.supervised import evaluate, train_supervised

SHIPPED = ('t-rnet-attn', 't-rnet', 't-cnn')
# The suite table's columns: the node's default first, then the per-task checkpoints.
# a table of a robot's own that no checkpoint was trained on (the source tree's config/)
LANDMARKS_TABLE = Path(__file__).resolve().parents[2] / 'config' / 'entities_office.yaml'
SUITE_CHECKPOINTS = (
    'pw_t-rnet-attn',
    'pw_t-cnn',
    'pw-local_t-rnet-attn',
    'pw-local_t-cnn',
    'pw-global_t-rnet-attn',
    'pw-global_t-cnn',
)


def forward_latency(model, grids, tokens, repeats: int = 50) -> float:
    """Median seconds of one forward pass."""
    with torch.no_grad():
        model(grids, tokens)
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            model(grids, tokens)
            times.append(time.perf_counter() - start)
    return float(np.median(times))


def _fmt(x, digits=2):
    return '-' if x is None else f'{x:.{digits}f}'


def markdown_table(rows: list[dict]) -> str:
    lines = [
        '| task | model | MSE | PQ | MD | HIT | paper MSE / PQ / MD | train min |',
        '| --- | --- | --- | --- | --- | --- | --- | --- |',
    ]
    for r in rows:
        paper = TASKS[r['task']].paper.get(r['model']) if r['task'] in TASKS else None
        paper_s = ' / '.join(_fmt(x) for x in paper) if paper else '-'
        lines.append(
            f'| {r["task"]} | {r["model"]} | {r["test"]["mse"]:.3f} | {r["test"]["pq"]:.3f} '
            f'| {r["test"]["md"]:.2f} | {_fmt(r["test"].get("hit"), 3)} | {paper_s} '
            f'| {r["train_seconds"] / 60:.1f} |'
        )
    return '\n'.join(lines) + '\n'


def value_map_row(task: str, model_name: str, path: Path, summary: dict, test) -> dict:
    """
    Return a trained checkpoint's row of value_map.json: its summary, test metrics, speed.

    The summary holds the run's recipe (training/recipe.py): every setting it trained with.
    """
    loaded = load_checkpoint(path)
    row = {
        'task': task,
        'model': model_name,
        **summary,
        'test': evaluate(loaded.model, loaded.vocab, test),
        'checkpoint': path.name,
        'commit': code_version(),
        'command': 'spatial-grounding reproduce --tasks {} --models {}'.format(task, model_name),
        # the kernels torch picked: the same code trains other weights on AVX2 than on AVX512
        'cpu_capability': torch.backends.cpu.get_cpu_capability(),
    }
    g1 = torch.from_numpy(test.grids[:1])
    tokens = torch.from_numpy(loaded.vocab.encode_batch(test.instructions[:512]))
    row['forward_seconds_one_map'] = forward_latency(loaded.model, g1, tokens[:1])
    row['forward_seconds_batch_512'] = forward_latency(
        loaded.model, torch.from_numpy(test.grids[:512]), tokens, repeats=5
    )
    return row


# Minutes of one row's training, alone on one thread, roughly: the longest rows start first, so
# the `jobs` processes finish together.
TRAIN_COST = {'t-rnet-attn': 4, 't-rnet': 3, 't-cnn': 2, 't-uvfa': 1}


def reproduce_row(
    task: str, model_name: str, data_dir: str, out: str, epochs_scale: float, start: float
) -> dict:
    """Train, calibrate (the node's default), evaluate and ship one row on one thread."""
    from ..grounder import DEFAULT_CHECKPOINT
    from .calibration import calibrate

    torch.set_num_threads(1)
    epochs = recipe(task, model_name).train.epochs
    tc = TrainConfig(epochs=max(1, int(epochs * epochs_scale)), threads=1)
    path, summary = train_supervised(
        task, model_name, data_dir, Path(out) / 'checkpoints', tc, progress=False
    )
    if path.stem == DEFAULT_CHECKPOINT:
        # the node's default declines by its calibrated confidence: fit it as shipped
        calibrate(str(path), data_dir, write=True)
    row = value_map_row(task, model_name, path, summary, load_task(task, 'test', data_dir))
    if model_name in SHIPPED:
        PACKAGED_DIR.mkdir(exist_ok=True)
        shutil.copy(path, PACKAGED_DIR / path.name)
    merge_results(Path(out) / 'value_map.json', row, (time.time() - start) / 60)
    return row


def reproduce_value_maps(
    data_dir: str,
    out: str,
    epochs_scale: float = 1.0,
    tasks=tuple(TASKS),
    models=('t-rnet-attn', 't-rnet', 't-cnn', 't-uvfa'),
    jobs: int = 2,
) -> list[dict]:
    """
    Train every (task, model) row in `jobs` processes, one thread each.

    On one thread training is deterministic whatever else runs (two threads made each other
    wait on a busy machine): the same code gives the same checkpoint, bit for bit. Each
    finished row replaces its row of out/value_map.json (a locked merge).
    """
    from concurrent.futures import ProcessPoolExecutor

    runs = sorted(
        ((t, m) for t in tasks for m in models),
        key=lambda tm: -TRAIN_COST[tm[1]] * TASKS[tm[0]].epochs * (8 if tm[0] == 'pw' else 1),
    )
    start = time.time()
    rows = []
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        futures = [
            pool.submit(reproduce_row, t, m, data_dir, out, epochs_scale, start) for t, m in runs
        ]
        for (t, m), f in tqdm(zip(runs, futures), total=len(runs), desc='make reproduce'):
            row = f.result()
            tqdm.write(f'{t} {m}: test {row["test"]} ({row["train_seconds"] / 60:.1f} min)')
            rows.append(row)
    return rows


def reproduce_suite(out: str | Path, sizes=(10, 32, 64), n: int = 100, seed: int = 0) -> dict:
    """Run the reference suite on every shipped PuddleWorld checkpoint: results/suite.{json,md}."""
    from . import suite

    # the default also on the relations composed from its groundings (RELATION_FAMILIES)
    results = {
        name: suite.run_suite(
            name, sizes, n, seed, progress=True,
            families=suite.SUITE_FAMILIES if name == SUITE_CHECKPOINTS[0] else suite.FAMILIES,
        )
        for name in SUITE_CHECKPOINTS
    }
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    meta = {
        'command': 'make reproduce-suite',
        'sizes': list(sizes),
        'n_per_family': n,
        'seed': seed,
    }
    (out / 'suite.json').write_text(json.dumps({'meta': meta, 'runs': results}, indent=1) + '\n')
    (out / 'suite.md').write_text(suite.markdown_table(results))
    # the default on a table it never saw, its landmarks named by name, alias and typo, worded
    # as people word them, and drawn as a robot's map draws them (footprints, unexplored
    # regions) with distances in metres
    runs = [
        *((naming, 'plain', False) for naming in NAMINGS),
        ('alias', 'paraphrase', False),
        ('name', 'plain', True),
        ('alias', 'metric', True),
    ]
    own = {
        f'{LANDMARKS_TABLE.stem} ({naming}, {wording}{", footprints" if drawn else ""})': (
            suite.run_suite(
                SUITE_CHECKPOINTS[0],
                sizes,
                n,
                seed,
                entities=LANDMARKS_TABLE,
                naming=naming,
                wording=wording,
                footprints=drawn,
            )
        )
        for naming, wording, drawn in runs
    }
    meta = {**meta, 'checkpoint': SUITE_CHECKPOINTS[0], 'entities': str(LANDMARKS_TABLE.name)}
    (out / 'landmarks.json').write_text(json.dumps({'meta': meta, 'runs': own}, indent=1) + '\n')
    (out / 'landmarks.md').write_text(suite.markdown_table(own))
    return results


def merge_results(results_path: Path, row: dict, run_minutes: float | None = None) -> None:
    """Add or replace one (task, model) row of value_map.json and its table (locked merge)."""
    meta = {
        'command': 'make reproduce',
        # wall-clock minutes of the run that wrote the newest row, from its start to that row
        'run_minutes': None if run_minutes is None else round(run_minutes, 1),
        'machine': platform.processor() or platform.machine(),
        'torch': torch.__version__,
    }
    merge_rows(results_path, [row], 'runs', {'meta': meta}, markdown_table)


# Each change of the clear-references recipe, turned off one at a time from the full recipe
# (same seed, same epochs): (name, TrainConfig overrides, ModelConfig overrides).
ABLATIONS = (
    ('recipe', {}, {}),
    ('MSE only (no goal cross-entropy)', {'goal_weight': 0.0}, {}),
    ('learned goal temperature', {'learn_goal_scale': True}, {}),
    ('gradient maps in cells (1 per 4.5)', {}, {'gradient_cells': 4.5}),
    ('no axial views in the head', {}, {'axial': False}),
    ('no far relation', {}, {'far': False}),
    ('no instruction in the head', {}, {'head_text': False}),
    ('no world-pickle instructions', {'world_instructions': False}, {}),
    ('no generated worlds', {'synthetic': 0}, {}),
)


def reproduce_ablation(
    data_dir: str,
    out: str,
    model: str = 't-rnet',
    epochs: int = 8,
    synthetic: int = 16000,
    threads: int = 2,
    seed: int = 0,
) -> list[dict]:
    """
    Train `model` on pw once per ABLATIONS row and score each run.

    Each run is scored on the suite (10x10 and 32x32) and the human test splits; the rows go
    to results/ablation.json and results/ablation.md.
    """
    from . import suite

    rows = []
    for name, train_overrides, model_overrides in ABLATIONS:
        tc = TrainConfig(
            **{
                'epochs': epochs,
                'synthetic': synthetic,
                'threads': threads,
                'seed': seed,
                **train_overrides,
            }
        )
        path, summary = train_supervised(
            'pw', model, data_dir, Path(out) / 'ablation' / name.split()[0], tc, **model_overrides
        )
        loaded = load_checkpoint(path)
        row = {
            'variant': name,
            'train_seconds': summary['train_seconds'],
            'suite': suite.run_suite(path, (10, 32), 40, seed, progress=False),
        }
        for task in ('pw-local', 'pw-global'):
            row[task] = evaluate(loaded.model, loaded.vocab, load_task(task, 'test', data_dir))
        print(f'{name}: suite {row["suite"]["sizes"]}, local {row["pw-local"]}', flush=True)
        rows.append(row)
    meta = {
        'command': f'spatial-grounding reproduce --ablation (pw, {model}, {epochs} epochs, '
        f'{synthetic} generated, seed {seed})'
    }
    Path(out).mkdir(parents=True, exist_ok=True)
    (Path(out) / 'ablation.json').write_text(
        json.dumps({'meta': meta, 'runs': rows}, indent=1) + '\n'
    )
    lines = [
        '| variant | suite hit 10x10 | suite hit 32x32 | PW local MD / HIT / MSE / PQ '
        '| PW global MD / HIT / MSE / PQ |',
        '| --- | --- | --- | --- | --- |',
    ]
    for r in rows:
        human = [
            f'{r[t]["md"]:.2f} / {r[t]["hit"]:.3f} / {r[t]["mse"]:.3f} / {r[t]["pq"]:.3f}'
            for t in ('pw-local', 'pw-global')
        ]
        lines.append(
            f'| {r["variant"]} | {r["suite"]["sizes"]["10"]["hit"]:.1%} '
            f'| {r["suite"]["sizes"]["32"]["hit"]:.1%} | {human[0]} | {human[1]} |'
        )
    (Path(out) / 'ablation.md').write_text('\n'.join(lines) + '\n')
    return rows


# --- the paper's RL rows: `make reproduce-rl` --------------------------------------------

# relative cost per episode, to start the longest runs first
RL_COST = {'t-rnet-attn': 10, 't-rnet': 3, 't-cnn': 1, 't-uvfa': 1}


def paper_rl() -> dict:
    """Return the paper's RL (PQ, MD) by model, then task: the head of results/rl.json."""
    table: dict = {}
    for task in RL_TASKS:
        for model, numbers in TASKS[task].paper_rl.items():
            table.setdefault(model, {})[task] = numbers
    return table


def rl_table(results: list[dict]) -> str:
    """Markdown: ours beside the paper's PQ / MD, under the caption line of results/rl.md."""
    lines = [
        'RL goal navigation (fitted value iteration, rewards only), test split; paper = '
        'Yang et al. 2020 Table 1.',
        '',
        '| task | model | PQ ours | PQ paper | MD ours | MD paper | episodes | minutes |',
        '| --- | --- | --- | --- | --- | --- | --- | --- |',
    ]
    for r in results:
        pq, md = TASKS[r['task']].paper_rl.get(r['model'], (None, None))
        lines.append(
            f'| {r["task"]} | {r["model"]} | {r["test"]["pq"]:.2f} | {_fmt(pq)} '
            f'| {r["test"]["md"]:.2f} | {_fmt(md)} | {r["episodes"]} '
            f'| {r["train_seconds"] / 60:.1f} |'
        )
    return '\n'.join(lines) + '\n'


def reproduce_rl(
    data_dir: str,
    out: str,
    tasks=RL_TASKS,
    models=('t-rnet-attn', 't-cnn'),
    scale: float = 1.0,
    jobs: int = 2,
    checkpoints: str = 'out',
) -> list[dict]:
    """
    Train every (model, task) by RL in `jobs` processes, one thread each.

    Each finished run replaces its row of out/rl.json and out/rl.md (results.merge_rows);
    rows of other tasks and models stay.
    """
    from concurrent.futures import ProcessPoolExecutor

    runs = sorted(
        ((m, t) for m in models for t in tasks),
        key=lambda mt: -TASKS[mt[1]].rl_episodes * RL_COST[mt[0]] * (3 if mt[1] == 'isi' else 1),
    )
    head = {
        'command': f'spatial-grounding reproduce-rl --data {data_dir} --out {out}',
        'paper': paper_rl(),
    }
    rows = []
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        futures = [
            pool.submit(
                train_rl,
                t,
                m,
                data_dir,
                checkpoints,
                RLConfig(episodes=max(1, int(TASKS[t].rl_episodes * scale))),
                progress=False,
            )
            for m, t in runs
        ]
        for (m, t), f in zip(runs, futures):
            path, summary = f.result()
            print(
                f'{t} {m}: PQ {summary["test"]["pq"]:.3f}  MD {summary["test"]["md"]:.2f}  '
                f'({summary["train_seconds"] / 60:.1f} min) -> {path}',
                flush=True,
            )
            rows = merge_rows(
                Path(out) / 'rl.json',
                [{**summary, 'checkpoint': str(path)}],
                'results',
                head,
                rl_table,
            )
    print(rl_table(rows))
    return rows
