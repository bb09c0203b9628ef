# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Natural instructions: what people say to a robot, on hand-drawn office and PuddleWorld maps.

The cases (data/natural/dev.yaml and held_out.yaml; requests.yaml and requests_held_out.yaml,
the clauses around a place: conditions, courtesies, what to do on arrival, lists of places, a
choice) were written by hand without reading how the grounder reads instructions. Each names a
map (rows of legend letters, a table, metres per cell), an instruction and what must come of
it: one goal cell, any of a set of cells (a landmark and the free cells beside it), a decline,
or an intent (a question and its referent, a stop, a sequence of steps). Every case goes
through Grounder.ground, one grounder per table.

Scores: of the cases that name a cell, the share whose goal is right; of the cases that must
send no goal, the share declined; of all, the share that sent a wrong goal (where none should
go, or the wrong cell) at confidence 0.5 or more; where the case has an intent, the share whose
`intent` (and a question's referent, a sequence's steps) matches. A ValueError counts as a
decline, and is counted apart. The held-out sets' per-case answers are left out of the
results: the lead sees their totals only.

    spatial-grounding natural --cases dev --out results/natural_dev.json   # and .md
"""

from __future__ import annotations

import json
from pathlib import Path
import sys

import numpy as np
from tqdm import tqdm
import yaml

from .calibration import expected_calibration_error
from ..grounder import Grounder

CASES_DIR = Path(__file__).resolve().parents[1] / 'data' / 'natural'
SETS = ('dev', 'held_out', 'requests', 'requests_held_out', 'relations', 'relations_held_out')
# the held-out sets: run for their totals only, their per-case answers left out
HELD_OUT = ('held_out', 'requests_held_out', 'relations_held_out')
CONFIDENT = 0.5
# the entity tables: the source tree's config/, or where the package installs it (share/)
TABLE_DIRS = (
    Path(__file__).resolve().parents[2] / 'config',
    Path(sys.prefix) / 'share' / 'spatial_grounding_ros' / 'config',
)
CATEGORIES = (
    'offset', 'filler', 'typo', 'unit', 'near', 'extreme', 'nearest', 'negation', 'question',
    'stop', 'sequence', 'correction', 'unsupported', 'unknown', 'missing', 'ambiguous', 'offmap',
    'obstacle', 'costly', 'long', 'noun', 'condition', 'courtesy', 'arrival', 'list', 'either',
    'side_of', 'side_of_missing',
)


def table_path(table: str) -> Path:
    """Return the YAML entity table `config/entities_<table>.yaml`, wherever it is installed."""
    for folder in TABLE_DIRS:
        path = folder / f'entities_{table}.yaml'
        if path.is_file():
            return path
    raise FileNotFoundError(f'entities_{table}.yaml not found in {[str(d) for d in TABLE_DIRS]}')


def table_names(table: str) -> list[str]:
    return list(yaml.safe_load(table_path(table).read_text())['names'])


def cases_path(cases: str | Path) -> Path:
    """Return the file of a named set (SETS) or a path as given."""
    return CASES_DIR / f'{cases}.yaml' if str(cases) in SETS else Path(cases)


def load_cases(cases: str | Path) -> dict:
    path = cases_path(cases)
    if not path.is_file():
        raise FileNotFoundError(f'{path}: natural cases file not found')
    data = yaml.safe_load(path.read_text())
    if not isinstance(data, dict) or 'maps' not in data or 'cases' not in data:
        raise ValueError(f'{path}: a cases file is a mapping with `maps` and `cases`')
    return data


def map_rows(m: dict) -> list[str]:
    return [row for row in m['rows'].splitlines() if row.strip()]


def build_grid(m: dict, names: list[str]) -> np.ndarray:
    """Return a map's (H, W) grid of entity indices: legend letter -> kind name -> index."""
    index = {letter: names.index(name) for letter, name in m['legend'].items()}
    return np.array([[index[ch] for ch in row] for row in map_rows(m)], dtype=np.int64)


def cells_of(step) -> set[tuple[int, int]]:
    """Return the right cells of an expected step: [r, c] or a list of them."""
    if step and isinstance(step[0], (list, tuple)):
        return {tuple(c) for c in step}
    return {tuple(step)}


def right_cells(expect: dict) -> set[tuple[int, int]] | None:
    """Return the cells a case's goal may be, or None when it must send no goal."""
    if 'goal' in expect:
        return {tuple(expect['goal'])}
    if 'near' in expect:
        return {tuple(c) for c in expect['near']}
    if expect.get('intent') == 'sequence':
        return cells_of(expect['goals'][0])
    return None


def step_goal(step):
    goal = getattr(step, 'goal', step)
    return None if goal is None else tuple(goal)


def score(case: dict, g, error: str | None) -> dict:
    """Return one case's answer and marks."""
    expect = case['expect']
    goal = None if g is None or g.goal is None else tuple(g.goal)
    confidence = 0.0 if g is None else float(g.confidence)
    cells = right_cells(expect)
    wrong = goal is not None and (cells is None or goal not in cells)
    out = {
        'map': case['map'],
        'category': case['category'],
        'names_cell': cells is not None,
        'goal': None if goal is None else list(goal),
        'confidence': round(confidence, 4),
        'reason': None if g is None else g.reason,
        'intent': None if g is None else getattr(g, 'intent', 'go'),
        'error': error,
        'right': cells is not None and goal in cells,
        'declined': goal is None,
        'wrong': wrong,
        'wrong_confident': wrong and confidence >= CONFIDENT,
    }
    if 'intent' in expect:
        out['intent_ok'] = out['intent'] == expect['intent']
        if expect['intent'] == 'question':
            referent = None if g is None or g.referent is None else list(g.referent)
            want = expect.get('referent')
            out['referent_ok'] = out['intent_ok'] and referent == (None if want is None
                                                                   else list(want))
        if expect['intent'] == 'sequence':
            steps = [] if g is None else list(getattr(g, 'steps', []) or [])
            out['steps_ok'] = len(steps) == len(expect['goals']) and all(
                step_goal(s) in cells_of(want) for s, want in zip(steps, expect['goals']))
    return out


def share(rows: list[dict], key: str) -> float | None:
    return float(np.mean([r[key] for r in rows])) if rows else None


def totals(rows: list[dict]) -> dict:
    """Return the scores of a group of answered cases."""
    named = [r for r in rows if r['names_cell']]
    no_goal = [r for r in rows if not r['names_cell']]
    out = {
        'n': len(rows),
        'n_goal': len(named),
        'n_no_goal': len(no_goal),
        'right': share(named, 'right'),
        'declined_of_goal': share(named, 'declined'),
        'declined': share(no_goal, 'declined'),
        'wrong_goal': share(rows, 'wrong'),
        'wrong_goal_confident': share(rows, 'wrong_confident'),
        'exceptions': sum(r['error'] is not None for r in rows),
    }
    for key in ('intent_ok', 'referent_ok', 'steps_ok'):
        marked = [r for r in rows if key in r]
        if marked:
            out[key] = share(marked, key)
            out[f'n_{key}'] = len(marked)
    return out


def run_natural(cases: str | Path = 'dev', checkpoint: str = 'pw_t-rnet-attn',
                progress: bool = True, detail: bool | None = None, **grounder_options) -> dict:
    """
    Ground every case of a cases file and score it (per case only when `detail`).

    `grounder_options`: more of Grounder.from_checkpoint's arguments (its defaults otherwise).
    """
    data = load_cases(cases)
    detail = str(cases) not in HELD_OUT if detail is None else detail
    grounders, names = {}, {}
    rows = []
    for case in tqdm(data['cases'], desc=f'natural {Path(str(cases)).stem}', disable=not progress):
        m = data['maps'][case['map']]
        table = m['table']
        if table not in grounders:
            grounders[table] = Grounder.from_checkpoint(
                checkpoint, entities=table_path(table), **grounder_options
            )
            names[table] = table_names(table)
        grid = build_grid(m, names[table])
        try:
            g, error = grounders[table].ground(grid, case['text'],
                                               cell_size=float(m['cell_size'])), None
        except ValueError as exc:
            g, error = None, str(exc)
        row = score(case, g, error)
        row['table'] = table
        if detail:
            row['text'] = case['text']
            row['expect'] = case['expect']
        rows.append(row)
    order = [c for c in CATEGORIES if any(r['category'] == c for r in rows)]
    order += sorted({r['category'] for r in rows} - set(order))
    return {
        'cases': str(cases),
        'checkpoint': checkpoint,
        'confident': CONFIDENT,
        'overall': totals(rows),
        'by_table': {t: totals([r for r in rows if r['table'] == t]) for t in sorted(grounders)},
        'by_category': {c: totals([r for r in rows if r['category'] == c]) for c in order},
        'ece': calibration(rows),
        'per_case': rows if detail else None,
    }


def calibration(rows: list[dict]) -> float | None:
    """Return the expected calibration error of the goals sent for cases that name a cell."""
    sent = [r for r in rows if r['names_cell'] and r['goal'] is not None]
    if not sent:
        return None
    return expected_calibration_error([r['confidence'] for r in sent], [r['right'] for r in sent])


def pct(x: float | None) -> str:
    return '-' if x is None else f'{x:.1%}'


def markdown(result: dict) -> str:
    """Return the scores as a Markdown table, one row per category and the totals."""
    lines = [
        f'Natural instructions ({result["cases"]}) through `{result["checkpoint"]}`: of the cases '
        'that name a cell, the share right; of those that must send no goal, the share '
        f'declined; of all, the share with a wrong goal at confidence >= {result["confident"]}; '
        'intents (question, stop, sequence) matched; ValueErrors (counted as declines).',
        '',
        '| category | n | right (n) | declined (n) | wrong goal, confident | intent | '
        'referent | steps | errors |',
        '| --- | --- | --- | --- | --- | --- | --- | --- | --- |',
    ]
    rows = [*result['by_category'].items(), *((f'**{t}**', r)
                                              for t, r in result['by_table'].items()),
            ('**all**', result['overall'])]
    for name, r in rows:
        lines.append(
            f'| {name} | {r["n"]} | {pct(r["right"])} ({r["n_goal"]}) | '
            f'{pct(r["declined"])} ({r["n_no_goal"]}) | {pct(r["wrong_goal_confident"])} | '
            f'{pct(r.get("intent_ok"))} | {pct(r.get("referent_ok"))} | '
            f'{pct(r.get("steps_ok"))} | {r["exceptions"]} |'
        )
    if result.get('ece') is not None:
        lines += ['', 'Expected calibration error of the goals sent for the cases that name a '
                  f'cell (10 bins): {result["ece"]:.3f}.']
    return '\n'.join(lines) + '\n'


def cmd_natural(args) -> int:
    result = run_natural(args.cases, args.checkpoint, progress=not args.json)
    text = markdown(result)
    if args.out:
        out = Path(args.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.with_suffix('.json').write_text(json.dumps(result, indent=1) + '\n')
        out.with_suffix('.md').write_text(text)
    print(json.dumps(result) if args.json else text)
    return 0


def register_cli(sub) -> None:
    p = sub.add_parser('natural', help='natural instructions on hand-drawn maps (SETS)')
    p.add_argument('--cases', default='dev', help=f'{", ".join(SETS)}, or a path to a cases YAML')
    p.add_argument('--checkpoint', default='pw_t-rnet-attn')
    p.add_argument('--json', action='store_true', help='print exactly one JSON object')
    p.add_argument('--out', default=None,
                   help='write the JSON here (results/natural_<name>.json) and a .md beside it')
    p.set_defaults(func=cmd_natural)
