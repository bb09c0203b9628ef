# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The natural-instruction case files are well-formed (no model runs here).

data/natural/dev.yaml and held_out.yaml: every map is a rectangle of its legend's letters, the
legend names kinds of its table (config/entities_<table>.yaml), every case names a map and a
known category, its expected cells lie inside the map and are not obstacles (a case that sends
no goal expects a decline or an intent), and held_out shares neither maps nor wordings with dev.
"""

from pathlib import Path

import pytest
from spatial_grounding_ros.core.entities import EntityTable
import yaml

REPO = Path(__file__).resolve().parents[1]
CASES = REPO / 'spatial_grounding_ros' / 'data' / 'natural'
# at least this many cases and maps; the requests sets: clauses around the place; the
# relations sets: a landmark picked by its side of another
SETS = {'dev': (240, 12), 'held_out': (160, 8), 'requests': (60, 3), 'requests_held_out': (55, 3),
        'relations': (30, 4), 'relations_held_out': (30, 4)}
WORDING = {
    'offset', 'filler', 'typo', 'unit', 'near', 'extreme', 'nearest', 'negation', 'question',
    'stop', 'sequence', 'correction', 'unsupported', 'unknown', 'missing', 'ambiguous', 'offmap',
    'obstacle', 'costly', 'long', 'noun',
}
REQUESTS = {'condition', 'courtesy', 'arrival', 'list', 'either'}
RELATIONS = {'side_of', 'side_of_missing'}
CATEGORIES = WORDING | REQUESTS | RELATIONS
SIZES = {'office': (10, 32), 'puddleworld': (10, 15)}
NO_GOAL = {'negation', 'question', 'stop', 'unsupported', 'unknown', 'missing', 'ambiguous',
           'offmap', 'obstacle', 'condition', 'either', 'side_of_missing'}


def load(name: str) -> dict:
    return yaml.safe_load((CASES / f'{name}.yaml').read_text())


def table(name: str) -> dict:
    return yaml.safe_load((REPO / 'config' / f'entities_{name}.yaml').read_text())


def rows(m: dict) -> list[str]:
    return [r for r in m['rows'].splitlines() if r.strip()]


def expected_cells(expect: dict) -> list[list[int]]:
    """Return every cell a case expects as a goal (goal, near, a sequence's steps)."""
    if 'goal' in expect:
        return [expect['goal']]
    if 'near' in expect:
        return list(expect['near'])
    cells = []
    for step in expect.get('goals', []):
        cells += step if isinstance(step[0], list) else [step]
    return cells


@pytest.mark.parametrize('name', SETS)
def test_maps_are_rectangles_of_their_tables_kinds(name):
    data = load(name)
    assert len(data['maps']) >= SETS[name][1]
    for map_name, m in data['maps'].items():
        kinds = table(m['table'])['names']
        assert float(m['cell_size']) > 0, map_name
        assert set(m['legend'].values()) <= set(kinds), (map_name, m['legend'])
        if '?' in m['legend']:
            assert m['legend']['?'] == 'unknown', map_name
        grid = rows(m)
        low, high = SIZES[m['table']]
        assert low <= len(grid) <= high and low <= len(grid[0]) <= high, map_name
        assert len({len(r) for r in grid}) == 1, f'{map_name}: rows of unequal length'
        assert set(''.join(grid)) <= set(m['legend']), f'{map_name}: a letter not in its legend'


@pytest.mark.parametrize('name', SETS)
def test_cases_are_well_formed(name):
    data = load(name)
    assert len(data['cases']) >= SETS[name][0]
    seen = set()
    for case in data['cases']:
        where = f'{name}: {case.get("text")!r}'
        assert case['map'] in data['maps'], where
        assert case['category'] in CATEGORIES, where
        assert isinstance(case['text'], str) and case['text'].strip(), where
        assert (case['map'], case['text']) not in seen, f'{where} twice'
        seen.add((case['map'], case['text']))
        m = data['maps'][case['map']]
        grid = rows(m)
        entities = table(m['table'])
        # no expected cell is impassable (a puddle, costly, may hold a goal; a near list names
        # a solid landmark's own cells beside the free ones)
        kinds = EntityTable.from_yaml(REPO / 'config' / f'entities_{m["table"]}.yaml')
        obstacles = {kinds.names[i] for i in kinds.kinds_that_are('impassable')}
        expect = case['expect']
        kinds = [k for k in ('goal', 'near', 'decline', 'intent') if k in expect]
        assert len(kinds) == 1, where
        if 'decline' in expect:
            assert expect['decline'] is True, where
        if 'intent' in expect:
            assert expect['intent'] in ('question', 'stop', 'sequence'), where
        if case['category'] in NO_GOAL:
            assert 'decline' in expect or expect.get('intent') in ('question', 'stop'), where
        if 'near' in expect:
            assert expect['near'], where
        if expect.get('intent') == 'sequence':
            assert len(expect['goals']) >= 2, where
        if expect.get('intent') == 'question' and expect['referent'] is not None:
            r, c = expect['referent']
            assert 0 <= r < len(grid) and 0 <= c < len(grid[0]), where
            assert m['legend'][grid[r][c]] not in obstacles | {entities['names'][0]}, where
        for r, c in expected_cells(expect):
            assert 0 <= r < len(grid) and 0 <= c < len(grid[0]), f'{where}: {(r, c)} off the map'
            assert m['legend'][grid[r][c]] not in obstacles, f'{where}: {(r, c)} an obstacle'


def test_every_category_in_both_sets():
    for name in SETS:
        kinds = {'requests': REQUESTS, 'relations': RELATIONS}.get(name.split('_')[0], WORDING)
        assert {c['category'] for c in load(name)['cases']} == kinds, name


@pytest.mark.parametrize('dev_name, held_name', [('dev', 'held_out'),
                                                 ('requests', 'requests_held_out'),
                                                 ('relations', 'relations_held_out')])
def test_held_out_shares_no_map_or_wording_with_dev(dev_name, held_name):
    dev, held = load(dev_name), load(held_name)
    assert not set(dev['maps']) & set(held['maps'])
    drawn = {m['rows'] for m in dev['maps'].values()}
    assert not drawn & {m['rows'] for m in held['maps'].values()}
    dev_texts = {c['text'].lower() for c in dev['cases']}
    assert not [c['text'] for c in held['cases'] if c['text'].lower() in dev_texts]
