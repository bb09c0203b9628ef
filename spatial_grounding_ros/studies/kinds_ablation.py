# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
PuddleWorld's own names read by name, by role, or by name but for "closest" (the Grounder's).

Each way is measured on the suite and the human test splits.
`spatial-grounding kinds-ablation --out results`: results/kinds_ablation.{json,md}. A table of
one's own always goes by role (its names are no kinds of the model); this measures what
delexicalising PuddleWorld's own names would cost or gain (docs/landmarks.md).
"""

from __future__ import annotations

import json
from pathlib import Path

from .honesty import human
from .suite import run_suite
from ..data.datasets import DEFAULT_DATA
from ..grounder import DEFAULT_CHECKPOINT, Grounder
from ..language.lexicon import KINDS_BY
from ..models.checkpoints import load_checkpoint
from ..training.options import ranged

# what each way is called in the table
SAID = {
    'name': 'by name but for closest (the Grounder)',
    'name-always': 'by name always',
    'role': 'by role always',
}


def run_kinds_ablation(data_dir=DEFAULT_DATA, sizes=(10, 32, 64), n: int = 100) -> dict:
    """Return each way's suite (all families, closest) and human-split figures."""
    out = {}
    for kinds_by in KINDS_BY:
        suite = run_suite(DEFAULT_CHECKPOINT, sizes, n, progress=True, kinds_by=kinds_by)
        grounder = Grounder(load_checkpoint(DEFAULT_CHECKPOINT), kinds_by=kinds_by)
        people = human(grounder, data_dir, progress=True)
        out[kinds_by] = {
            'suite': {s: suite['sizes'][s]['hit'] for s in suite['sizes']},
            'closest': {s: v['hit'] for s, v in suite['families']['closest'].items()},
            'human': {
                task: {'md': r['md_best'], 'hit': r['hit_best']} for task, r in people.items()
            },
        }
    return out


def markdown(result: dict) -> str:
    sizes = list(next(iter(result.values()))['suite'])
    lines = [
        '| landmark kinds | suite ' + ' / '.join(sizes) + ' | closest ' + ' / '.join(sizes)
        + ' | PW local MD (HIT) | PW global MD (HIT) |',
        '| --- | --- | --- | --- | --- |',
    ]
    for kinds_by, r in result.items():
        lines.append(
            f'| {SAID[kinds_by]} | '
            + ' / '.join(f'{r["suite"][s]:.1%}' for s in sizes)
            + ' | '
            + ' / '.join(f'{r["closest"][s]:.0%}' for s in sizes)
            + ' | '
            + ' | '.join(
                f'{r["human"][t]["md"]:.3f} ({r["human"][t]["hit"]:.3f})'
                for t in ('pw-local', 'pw-global')
            )
            + ' |'
        )
    return '\n'.join(lines) + '\n'


def cmd_kinds_ablation(args) -> int:
    result = run_kinds_ablation(args.data, tuple(args.sizes), args.n)
    table = markdown(result)
    print(table)
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        meta = {'command': 'spatial-grounding kinds-ablation --out results', 'n': args.n}
        (out / 'kinds_ablation.json').write_text(
            json.dumps({'meta': meta, 'runs': result}, indent=1) + '\n'
        )
        (out / 'kinds_ablation.md').write_text(table)
    return 0


def register_cli(sub) -> None:
    p = sub.add_parser(
        'kinds-ablation',
        help="PuddleWorld's names read by name, by role, or by name but for closest",
    )
    p.add_argument('--data', default=DEFAULT_DATA)
    p.add_argument('--sizes', nargs='+', type=ranged(int, low=5), default=[10, 32, 64])
    p.add_argument('--n', type=ranged(int, low=1), default=100, help='suite worlds a family')
    p.add_argument('--out', default=None, help='write kinds_ablation.json and .md here')
    p.set_defaults(func=cmd_kinds_ablation)
