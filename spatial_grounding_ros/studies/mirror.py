# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
`spatial-grounding mirror-study`: what mirror averaging earns, and how often it runs.

The default grounded three ways, each through Grounder.ground one map at a time: never with
its mirror images, with them where the map alone leaves it unsure (the default's
mirror_average_below), and with them on every map up to mirror_average_cells. Each is
scored on the suite (every family), the human test splits (best-cell MD and HIT, declined),
the natural wordings (dev and held-out: right, confidently wrong) and calibration (ECE over
the suite and the human splits), beside the share of groundings it averaged.
"""

from __future__ import annotations

import json
from pathlib import Path

from tqdm import tqdm

from .calibration import expected_calibration_error
from .honesty import answered, HUMAN_TASKS
from .natural import run_natural
from .suite import SUITE_FAMILIES, suite_worlds
from ..core import world
from ..data.datasets import DEFAULT_DATA, load_task
from ..grounder import Grounder, MIRROR_AVERAGE_BELOW, MIRROR_AVERAGE_CELLS
from ..training.options import ranged

# (name, mirror_average_cells, mirror_average_below)
SETTINGS = (
    ('never', 0, 0.0),
    (f'below {MIRROR_AVERAGE_BELOW:g} (the default)', MIRROR_AVERAGE_CELLS, MIRROR_AVERAGE_BELOW),
    ('every map', MIRROR_AVERAGE_CELLS, 1.0),
)


def scored(grounder: Grounder, cases, progress: bool, desc: str) -> dict:
    """Ground (grid, instruction, goal) cases; return answered()'s rates and the share averaged."""
    before = grounder.mirror_averaged
    groundings, goals = [], []
    for grid, text, goal in tqdm(cases, desc=desc, disable=not progress, leave=False):
        groundings.append(grounder.ground(grid, text))
        goals.append(goal)
    out = answered(groundings, goals)
    out['mirrored'] = (grounder.mirror_averaged - before) / max(1, len(groundings))
    return out


def run_mirror_study(
    checkpoint: str = 'pw_t-rnet-attn',
    data_dir=DEFAULT_DATA,
    sizes=(10, 32, 64),
    n: int = 100,
    progress: bool = True,
    natural: bool = True,
) -> dict:
    """Score each of SETTINGS (`natural`: on the natural wordings too)."""
    result = {'checkpoint': checkpoint, 'sizes': list(sizes), 'n_per_family': n, 'settings': {}}
    for name, cells, below in SETTINGS:
        options = {'mirror_average_cells': cells, 'mirror_average_below': below}
        # every goal kept, as the honesty study keeps them: min_confidence applies in answered()
        grounder = Grounder.from_checkpoint(checkpoint, min_confidence=0.0, **options)
        row = {**options, 'suite': {}, 'human': {}}
        for size in sizes:
            cases = [
                (w.grid, w.instruction, w.goal)
                for f in SUITE_FAMILIES
                for w in suite_worlds(f, size, n, 0)
            ]
            row['suite'][str(size)] = scored(grounder, cases, progress, f'{name}: suite {size}')
        if (Path(data_dir) / 'puddleworld').is_dir():
            for task in HUMAN_TASKS:
                test = load_task(task, 'test', data_dir)
                cases = zip(test.grids, test.instructions, world.argmax_cells(test.values))
                row['human'][task] = scored(grounder, list(cases), progress, f'{name}: {task}')
        runs = [*row['suite'].values(), *row['human'].values()]
        row['ece'] = expected_calibration_error(
            [c for r in runs for c in r.pop('confidence')],
            [c for r in runs for c in r.pop('correct')],
        )
        for cases in ('dev', 'held_out') if natural else ():
            found = run_natural(cases, checkpoint, progress=False, detail=False, **options)
            row[f'natural_{cases}'] = found['overall']
        result['settings'][name] = row
    return result


def pct(x) -> str:
    return '-' if x is None else f'{100 * x:.1f}%'


def markdown(result: dict) -> str:
    """Return the study's table: one column per setting."""
    names = list(result['settings'])
    rows = result['settings']
    lines = ['| | ' + ' | '.join(names) + ' |', '| --- |' + ' --- |' * len(names)]

    def line(label, cell):
        lines.append(f'| {label} | ' + ' | '.join(cell(rows[n]) for n in names) + ' |')

    sizes = result['sizes']
    line(
        'suite, every family, ' + ' / '.join(f'{s}x{s}' for s in sizes) + ': right cell',
        lambda r: ' / '.join(pct(r['suite'][str(s)]['hit_best']) for s in sizes),
    )
    for task in HUMAN_TASKS:
        line(
            f'human {task}: best-cell MD / HIT / declined',
            lambda r, t=task: (
                f'{r["human"][t]["md_best"]:.2f} / {r["human"][t]["hit_best"]:.3f} / '
                f'{pct(r["human"][t]["declined"])}' if t in r['human'] else '-'
            ),
        )
    for cases in ('dev', 'held_out'):
        line(
            f'natural {cases.replace("_", "-")}: right / confidently wrong',
            lambda r, c=cases: (
                f'{pct(r[f"natural_{c}"]["right"])} / '
                f'{pct(r[f"natural_{c}"]["wrong_goal_confident"])}'
                if f'natural_{c}' in r else '-'
            ),
        )
    line('ECE, suite and human', lambda r: f'{r["ece"]:.4f}')
    line(
        'groundings averaged: suite ' + ' / '.join(str(s) for s in sizes) + '; human',
        lambda r: ' / '.join(pct(r['suite'][str(s)]['mirrored']) for s in sizes)
        + '; '
        + ' / '.join(pct(r['human'][t]['mirrored']) for t in HUMAN_TASKS if t in r['human']),
    )
    return '\n'.join(lines) + '\n'


def cmd_mirror_study(args) -> int:
    result = run_mirror_study(args.checkpoint, args.data, tuple(args.sizes), args.n)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / 'mirror.json').write_text(json.dumps(result, indent=1) + '\n')
    (out / 'mirror.md').write_text(markdown(result))
    print(markdown(result), end='')
    return 0


def register_cli(sub) -> None:
    p = sub.add_parser(
        'mirror-study',
        help='what mirror averaging earns (suite, human splits, natural wordings, ECE) and '
        'how often it runs: never, where unsure (the default), on every map',
    )
    p.add_argument('--checkpoint', default='pw_t-rnet-attn')
    p.add_argument('--data', default=DEFAULT_DATA)
    p.add_argument('--sizes', type=ranged(int, low=5), nargs='+', default=[10, 32, 64])
    p.add_argument('--n', type=ranged(int, low=1), default=100, help='worlds per family and size')
    p.add_argument('--out', default='results', help='writes mirror.json and mirror.md here')
    p.set_defaults(func=cmd_mirror_study)
