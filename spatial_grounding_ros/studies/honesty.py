# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Honest answers: the grounder declines what no cell answers, and only that.

Three measurements, each one map at a time through Grounder.ground (the node's path):

- generated unanswerable cases of each kind (data/unanswerable.py) at 10x10 and 32x32: the
  share declined, and the share declined with the right reason;
- the reference suite's clear instructions: the share declined, and the exact-goal rate
  (a declined one counts as a miss);
- the human PuddleWorld test splits: the share declined, the best cell's MD and exact-goal
  rate, the exact-goal rate of the answers given and of all, and how well calibrated the
  confidence is: the expected calibration error of the answers given, on the suite and the
  human splits together (and apart).

    spatial-grounding honesty --out results     # results/honesty.json, results/honesty.md
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from tqdm import tqdm

from .calibration import expected_calibration_error
from .suite import suite_worlds
from ..core import world
from ..data.datasets import DEFAULT_DATA, load_task
from ..data.generator import FAMILIES
from ..data.unanswerable import cases, KINDS, REASONS, table_of
from ..grounder import DEFAULT_MIN_CONFIDENCE, Grounder
from ..training.options import ranged

HUMAN_TASKS = ('pw-local', 'pw-global')


def unanswerable(grounder: Grounder, sizes, n: int, seed: int, progress: bool) -> dict:
    out = {}
    jobs = [(kind, size) for size in sizes for kind in KINDS]
    for kind, size in tqdm(jobs, desc='unanswerable', disable=not progress):
        table = table_of(kind)
        of_table = grounder if table == grounder.entities else Grounder(grounder.loaded, table)
        found = [reason(of_table.ground(g, t)) for g, t in cases(kind, size, n, seed)]
        out.setdefault(kind, {})[str(size)] = {
            'declined': float(np.mean([r is not None for r in found])),
            'right_reason': float(np.mean([r == REASONS[kind] for r in found])),
            'n': n,
        }
    return out


# the min_confidence values whose trade-off the study tables (docs/honest-answers.md)
THRESHOLDS = (0.0, 0.05, 0.1, 0.15, 0.2, 0.3, 0.5)


def reason(grounding) -> str | None:
    """Return a grounding's reason code at the shipped min_confidence."""
    if grounding.goal is not None and grounding.confidence < DEFAULT_MIN_CONFIDENCE:
        return 'low-confidence'
    return grounding.reason_code


def answered(groundings, goals, min_confidence: float = DEFAULT_MIN_CONFIDENCE) -> dict:
    """
    Decline rate, hit rates, and what calibration needs, of groundings and their goals.

    The groundings are made at min_confidence 0; a goal under `min_confidence` counts as the
    grounder's decline (its last check), and THRESHOLDS' rates are given beside.
    """
    hits = np.array([g.best == tuple(goal) for g, goal in zip(groundings, goals)])
    sent = np.array([g.goal is not None for g in groundings])
    sure = np.array([g.confidence for g in groundings])
    given = sent & (sure >= min_confidence)
    distance = [
        abs(g.best[0] - goal[0]) + abs(g.best[1] - goal[1]) for g, goal in zip(groundings, goals)
    ]
    return {
        'n': len(groundings),
        'md_best': float(np.mean(distance)),
        'hit_best': float(hits.mean()),
        'declined': float(1 - given.mean()),
        'hit_all': float((hits & given).mean()),
        'hit_answered': float(hits[given].mean()) if given.any() else None,
        'confidence': [g.confidence for g, a in zip(groundings, given) if a],
        'correct': [bool(h) for h, a in zip(hits, given) if a],
        'reasons': sorted(
            {g.reason_code for g in groundings if g.reason_code}
            | ({'low-confidence'} if (sent & ~given).any() else set())
        ),
        'thresholds': {
            str(t): {
                'declined': float(1 - (sent & (sure >= t)).mean()),
                'hit_all': float((hits & sent & (sure >= t)).mean()),
            }
            for t in THRESHOLDS
        },
    }


def clear(grounder: Grounder, sizes, n: int, progress: bool) -> dict:
    out = {}
    for size in tqdm(sizes, desc='suite', disable=not progress):
        worlds = [w for f in FAMILIES for w in suite_worlds(f, size, n, 0)]
        out[str(size)] = answered([grounder.ground(w.grid, w.instruction) for w in worlds],
                                  [w.goal for w in worlds])
    return out


def human(grounder: Grounder, data_dir, progress: bool) -> dict:
    out = {}
    for task in HUMAN_TASKS:
        test = load_task(task, 'test', data_dir)
        groundings = [
            grounder.ground(g, t)
            for g, t in tqdm(zip(test.grids, test.instructions), desc=task, total=len(test),
                             disable=not progress)
        ]
        out[task] = answered(groundings, world.argmax_cells(test.values))
    return out


def run_honesty(
    checkpoint: str = 'pw_t-rnet-attn',
    data_dir=DEFAULT_DATA,
    sizes=(10, 32),
    n: int = 200,
    suite_n: int = 100,
    seed: int = 1,
    progress: bool = True,
) -> dict:
    # every goal is kept here; the shipped min_confidence is applied to the answers, and the
    # other THRESHOLDS beside it
    grounder = Grounder.from_checkpoint(checkpoint, min_confidence=0.0)
    result = {
        'checkpoint': checkpoint,
        'temperature': grounder.temperature,
        'min_confidence': DEFAULT_MIN_CONFIDENCE,
        'unanswerable': unanswerable(grounder, sizes, n, seed, progress),
        'suite': clear(grounder, (*sizes, 64), suite_n, progress),
    }
    if (Path(data_dir) / 'puddleworld').is_dir():
        result['human'] = human(grounder, data_dir, progress)
    parts = {
        'suite': list(result['suite'].values()),
        'human': list(result.get('human', {}).values()),
    }
    result['ece'] = {}
    for name, runs in {**parts, 'both': parts['suite'] + parts['human']}.items():
        conf = [c for r in runs for c in r['confidence']]
        if conf:
            result['ece'][name] = expected_calibration_error(
                conf, [c for r in runs for c in r['correct']]
            )
    for runs in parts.values():  # the per-example lists served the errors above
        for r in runs:
            r.pop('confidence'), r.pop('correct')
    return result


def markdown(result: dict) -> str:
    sizes = list(next(iter(result['unanswerable'].values())))
    lines = [
        f'Honest answers of `{result["checkpoint"]}` (temperature {result["temperature"]:.3g}), '
        'one map at a time. Unanswerable cases: share declined / share with the right reason.',
        '',
        '| case | expected reason | ' + ' | '.join(f'{s}x{s}' for s in sizes) + ' |',
        '| --- | --- | ' + ' | '.join('---' for _ in sizes) + ' |',
    ]
    for kind, per in result['unanswerable'].items():
        cells = [f'{per[s]["declined"]:.1%} / {per[s]["right_reason"]:.1%}' for s in sizes]
        lines.append(f'| {kind} | `{REASONS[kind]}` | ' + ' | '.join(cells) + ' |')
    lines += [
        '',
        '| clear or human | n | declined | hit of all | hit of the answers | best cell: MD / hit '
        '| reasons given |',
        '| --- | --- | --- | --- | --- | --- | --- |',
    ]
    rows = [(f'suite {s}x{s}', r) for s, r in result['suite'].items()]
    rows += [(f'{t} test', r) for t, r in result.get('human', {}).items()]
    for name, r in rows:
        answered_hit = '-' if r['hit_answered'] is None else f'{r["hit_answered"]:.1%}'
        lines.append(
            f'| {name} | {r["n"]} | {r["declined"]:.1%} | {r["hit_all"]:.1%} | {answered_hit} | '
            f'{r["md_best"]:.2f} / {r["hit_best"]:.1%} | '
            + (', '.join(r['reasons']) or '-')
            + ' |'
        )
    lines += [
        '',
        f'The shipped min_confidence is {result["min_confidence"]:g}. Declined / hit of all at '
        'other values:',
        '',
        '| min_confidence | ' + ' | '.join(name for name, _ in rows) + ' |',
        '| --- | ' + ' | '.join('---' for _ in rows) + ' |',
    ]
    for t in THRESHOLDS:
        lines.append(f'| {t:g} | ' + ' | '.join(
            f'{r["thresholds"][str(t)]["declined"]:.1%} / {r["thresholds"][str(t)]["hit_all"]:.1%}'
            for _, r in rows
        ) + ' |')
    lines += ['', 'Expected calibration error of the answers given (10 bins): '
              + ', '.join(f'{k} {v:.3f}' for k, v in result['ece'].items()) + '.']
    return '\n'.join(lines) + '\n'


def cmd_honesty(args) -> int:
    result = run_honesty(args.checkpoint, args.data, tuple(args.sizes), args.n, args.suite_n,
                         args.seed, progress=not args.json)
    text = markdown(result)
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / 'honesty.json').write_text(json.dumps(result, indent=1) + '\n')
        (out / 'honesty.md').write_text(text)
    print(json.dumps(result) if args.json else text)
    return 0


def register_cli(sub) -> None:
    p = sub.add_parser('honesty', help='declines, reasons and calibration on generated cases')
    p.add_argument('--checkpoint', default='pw_t-rnet-attn')
    p.add_argument('--data', default=DEFAULT_DATA)
    p.add_argument('--sizes', type=ranged(int, low=5), nargs='+', default=[10, 32])
    p.add_argument('--n', type=ranged(int, low=1), default=200, help='cases per kind and size')
    p.add_argument('--suite-n', type=ranged(int, low=1), default=100,
                   help='suite worlds per family and size')
    p.add_argument('--seed', type=ranged(int, low=0), default=1)
    p.add_argument('--json', action='store_true', help='print exactly one JSON object')
    p.add_argument('--out', default=None, help='write honesty.json and honesty.md here')
    p.set_defaults(func=cmd_honesty)
