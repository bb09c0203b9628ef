# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The locked merge of results files (results.merge_rows), which value_map.json and rl.json share.

Processes that merge into the same file at the same time keep each other's rows, and the writers
of results/*.md give back the committed tables from the committed JSON.
"""

import json
import multiprocessing
from pathlib import Path

from spatial_grounding_ros.studies.results import merge_rows

RESULTS = Path(__file__).resolve().parents[1] / 'results'


def table(rows):
    return ''.join(f'| {r["task"]} | {r["model"]} |\n' for r in rows)


def merge_many(path: str, model: str, n: int, start) -> None:
    start.wait()  # both processes begin together
    for i in range(n):
        row = {'task': f'task{i:02d}', 'model': model, 'value': i}
        merge_rows(path, [row], 'results', {'command': model}, table)


def test_concurrent_merges_keep_both_processes_rows(tmp_path):
    path = tmp_path / 'rl.json'
    context = multiprocessing.get_context('spawn')
    start = context.Barrier(2)
    workers = [
        context.Process(target=merge_many, args=(str(path), model, 40, start))
        for model in ('model-a', 'model-b')
    ]
    for w in workers:
        w.start()
    for w in workers:
        w.join(timeout=120)
    assert [w.exitcode for w in workers] == [0, 0]
    rows = json.loads(path.read_text())['results']
    assert sorted((r['task'], r['model']) for r in rows) == sorted(
        (f'task{i:02d}', m) for i in range(40) for m in ('model-a', 'model-b')
    )
    assert path.with_suffix('.md').read_text() == table(rows)
    assert not list(tmp_path.glob('.*.tmp'))


def test_merge_replaces_own_rows_keeps_others_in_task_order(tmp_path):
    path = tmp_path / 'value_map.json'
    merge_rows(path, [{'task': 'isi', 'model': 'm', 'v': 1}], 'runs', {'meta': 1})
    merge_rows(path, [{'task': 'pw-local', 'model': 'm', 'v': 2}], 'runs', {'meta': 2})
    merge_rows(path, [{'task': 'isi', 'model': 'm', 'v': 3}], 'runs', {'meta': 3})
    got = json.loads(path.read_text())
    assert got == {
        'meta': 3,
        'runs': [
            {'task': 'pw-local', 'model': 'm', 'v': 2},
            {'task': 'isi', 'model': 'm', 'v': 3},
        ],
    }
    assert not path.with_suffix('.md').exists()


def test_table_writers_give_the_committed_tables():
    # imported here: the merging processes above import this module, and need no torch
    from spatial_grounding_ros.studies.reproduce import markdown_table, rl_table

    value_map = json.loads((RESULTS / 'value_map.json').read_text())['runs']
    assert markdown_table(value_map) == (RESULTS / 'value_map.md').read_text()
    rl = json.loads((RESULTS / 'rl.json').read_text())['results']
    assert rl_table(rl) == (RESULTS / 'rl.md').read_text()
