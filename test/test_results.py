# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The published results hold together.

Each shipped checkpoint evaluates to its row of results/value_map.json within what another CPU can
change, the results/*.md tables are those rows, the README's tables are the results/*.md files,
and the figures its Results summary states in words are those of the results/*.json files.
"""

import json
from pathlib import Path
import re

import pytest
from spatial_grounding_ros import cli
from spatial_grounding_ros.core.tasks import TASKS
from spatial_grounding_ros.data.generator import RELATION_FAMILIES
from spatial_grounding_ros.models.checkpoints import load_checkpoint, PACKAGED_DIR
from spatial_grounding_ros.shapeworld.reproduce import PAPER_ACC
from spatial_grounding_ros.studies import bench

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / 'results'
# the value-map checkpoints; ShapeWorld's classifiers have results/shapeworld.json
SHIPPED = sorted(
    p.name for p in PACKAGED_DIR.glob('*.pt') if not p.name.startswith('shapeworld_')
)


def value_map_rows() -> list[dict]:
    return json.loads((RESULTS / 'value_map.json').read_text())['runs']


def test_every_shipped_checkpoint_has_a_results_row():
    assert SHIPPED, f'no checkpoints in {PACKAGED_DIR}'
    named = [r.get('checkpoint') for r in value_map_rows()]
    for name in SHIPPED:
        assert named.count(name) == 1, f'{name}: {named.count(name)} rows in value_map.json'


@pytest.mark.parametrize('checkpoint', SHIPPED)
def test_shipped_checkpoint_evaluates_to_its_results_row(checkpoint, data_dir, capsys):
    """
    Check that `spatial-grounding eval` reproduces a row of value_map.json.

    `spatial-grounding eval --checkpoint <task>_<model> --task <task>` gives the row of
    value_map.json written for that checkpoint (row and file found by name, nothing copied
    here), within what another CPU's rounding can change:
    - MD: a near-tie can flip one map's argmax, which moves that map's distance by at most
      the map's diameter, (H - 1) + (W - 1) (18 on 10x10, 24 on ISI's 13x13), so the mean
      by diameter / n; we allow two such flips: 0.090 on PW local (n 399), 0.132 on PW global
      (272), 0.054 on pw (671), 0.015 on ISI (3177). A checkpoint trained otherwise moves
      MD by tenths (the table's models differ by 0.1 to 2).
    - HIT (if the row has it): two flipped maps, 2 / n.
    - PQ: the softmax policy is continuous in the values, so no flip; rounding can add or
      drop one sweep of score iteration on a map, which moves its mean score by under
      0.01 / cells: 1e-3 on the mean PQ is far above that and far below a model's change.
    - MSE: continuous, float32 rounding: 1e-4.
    - n: exact.
    """
    [row] = [r for r in value_map_rows() if r.get('checkpoint') == checkpoint]
    name = checkpoint.removesuffix('.pt')
    assert name == f'{row["task"]}_{row["model"]}'
    header = load_checkpoint(name).header
    assert header['model'] == row['model'] and header['task'] == row['task']
    assert (
        cli.main(
            [
                'eval',
                '--checkpoint',
                name,
                '--task',
                row['task'],
                '--data',
                str(data_dir),
                '--json',
            ]
        )
        == 0
    )
    got = json.loads(capsys.readouterr().out)
    expected = row['test']
    n = expected['n']
    assert got['n'] == n
    shape = (13, 13) if row['task'] == 'isi' else (10, 10)
    tolerance = {
        'md': 2 * (shape[0] - 1 + shape[1] - 1) / n,
        'hit': 2 / n,
        'pq': 1e-3,
        'mse': 1e-4,
    }
    for metric in ('mse', 'pq', 'md', 'hit'):
        if metric in expected:
            assert got[metric] == pytest.approx(expected[metric], abs=tolerance[metric]), metric


# --- tables ------------------------------------------------------------------------------


def tables(text: str) -> list[list[list[str]]]:
    """
    Return every markdown table in `text` as rows of stripped cells.

    Every markdown table in `text`, as rows of stripped cells (header row first, the
    --- row left out).
    """
    found, current = [], []
    for line in text.splitlines() + ['']:
        if line.startswith('|'):
            cells = [c.strip() for c in line.strip().strip('|').split('|')]
            if not all(set(c) <= set('-: ') for c in cells):
                current.append(cells)
        elif current:
            found.append(current)
            current = []
    return found


def readme_section(heading: str) -> str:
    """Return the text from `## heading` to the next `## `, in the README or a docs/ page."""
    for page in [REPO / 'README.md', *sorted((REPO / 'docs').glob('*.md'))]:
        text = page.read_text()
        start = text.find(f'\n## {heading}\n')
        if start >= 0:
            end = text.find('\n## ', start + 1)
            return text[start:end if end > 0 else None]
    raise AssertionError(f'no section "## {heading}" in the README or docs/')


@pytest.mark.parametrize(
    'heading, results_file',
    [
        ('Results: value maps', 'value_map.md'),
        ('Results: RL', 'rl.md'),
        ('Results: clear references', 'suite.md'),
        ('Results: clear references', 'ablation.md'),
        ('Benchmarks', 'bench.md'),
        ('Mirror averaging', 'mirror.md'),
        ('Results: ShapeWorld', 'shapeworld.md'),
        ('Results: robustness', 'robustness.md'),
        ('Results: your own landmarks', 'landmarks.md'),
        ('Results: honest answers', 'honesty.md'),
        ('Results: the node under noise words', 'robustness_grounder.md'),
        ('Results: landmark kinds by name or by role', 'kinds_ablation.md'),
        ('Results: natural wording (dev)', 'natural_dev.md'),
        ('Results: natural wording (held out)', 'natural_held_out.md'),
        ('Results: requests (dev)', 'natural_requests.md'),
        ('Results: requests (held out)', 'natural_requests_held_out.md'),
        ('Results: a landmark on a side of another (dev)', 'natural_relations.md'),
        ('Results: a landmark on a side of another (held out)', 'natural_relations_held_out.md'),
    ],
)
def test_readme_table_is_the_results_file(heading, results_file):
    """
    Check that the README's table of a results file is that file's table.

    The table under the README heading with results/<file>'s header is that file's table
    cell for cell (and the file's caption line is there too): what `make reproduce` wrote is
    what the README says.
    """
    source = (RESULTS / results_file).read_text()
    section = readme_section(heading)
    for expected in tables(source):
        [got] = [t for t in tables(section) if t[0] == expected[0]] or [tables(section)[0]]
        assert len(got) == len(expected), (
            f'README has {len(got)} rows, {results_file} {len(expected)}'
        )
        for i, (a, b) in enumerate(zip(got, expected)):
            assert a == b, f'row {i} differs: README {a} vs {results_file} {b}'
    for line in source.splitlines():
        if line.strip() and not line.startswith('|'):
            assert line in section, f"{results_file}'s line {line!r} is not in the README"


def rows_by_header(table: list[list[str]]) -> list[dict]:
    header, *rows = table
    return [dict(zip(header, row)) for row in rows]


def same_number(cell: str, value: float) -> bool:
    """`cell` is `value` written with the cell's own number of decimals."""
    decimals = len(cell.partition('.')[2])
    return cell == f'{value:.{decimals}f}'


def test_mirror_table_is_the_json():
    """results/mirror.md is the table `spatial-grounding mirror-study` makes of mirror.json."""
    from spatial_grounding_ros.studies import mirror

    result = json.loads((RESULTS / 'mirror.json').read_text())
    assert (RESULTS / 'mirror.md').read_text() == mirror.markdown(result)


def test_value_map_table_is_the_json():
    """
    Check results/value_map.md against value_map.json.

    One row per value_map.json run, its MSE, PQ and MD (and HIT when there) that run's test metrics
    at the table's precision.
    """
    [table] = tables((RESULTS / 'value_map.md').read_text())
    runs = {(r['task'], r['model']): r for r in value_map_rows()}
    rows = rows_by_header(table)
    assert {(r['task'], r['model']) for r in rows} == set(runs)
    for row in rows:
        run = runs[row['task'], row['model']]
        metrics = [h for h in row if h.lower() in run['test'] and h.lower() != 'n']
        assert {'MSE', 'PQ', 'MD'} <= set(metrics)
        for h in metrics:
            assert same_number(row[h], run['test'][h.lower()]), (row['task'], row['model'], h)


def test_rl_table_is_the_json():
    """
    Check results/rl.md against rl.json.

    One row per rl.json result, its PQ and MD (ours) that run's test metrics at the table's
    precision, and its episodes.
    """
    [table] = tables((RESULTS / 'rl.md').read_text())
    runs = {
        (r['task'], r['model']): r
        for r in json.loads((RESULTS / 'rl.json').read_text())['results']
    }
    rows = rows_by_header(table)
    assert {(r['task'], r['model']) for r in rows} == set(runs)
    for row in rows:
        run = runs[row['task'], row['model']]
        for h in [h for h in row if re.fullmatch(r'\w+ ours', h)]:
            assert same_number(row[h], run['test'][h.split()[0].lower()]), (row['task'], h)
        assert int(row['episodes']) == run['episodes']


def test_every_rl_row_is_at_least_the_papers():
    """The README's claim: on every RL row PQ is at least the paper's and MD at most its."""
    for r in json.loads((RESULTS / 'rl.json').read_text())['results']:
        pq, md = TASKS[r['task']].paper_rl[r['model']]
        assert r['test']['pq'] >= pq and r['test']['md'] <= md, (r['task'], r['model'])


def test_suite_table_is_the_json():
    """results/suite.md: each checkpoint's hit per family and size is suite.json's."""
    runs = json.loads((RESULTS / 'suite.json').read_text())['runs']
    [table] = tables((RESULTS / 'suite.md').read_text())
    header, *rows = table
    assert header[2:] == list(runs)
    for row in rows:
        family, size = row[0], row[1]
        for cell, run in zip(row[2:], runs.values()):
            if family != '**all**' and family not in run['families']:  # a family it did not run
                assert cell == '-', (family, size)
                continue
            summary = run['sizes'][size] if family == '**all**' else run['families'][family][size]
            assert cell.split()[0].strip('*') == f'{summary["hit"]:.1%}', (family, size)


def test_bench_table_is_the_json():
    """results/bench.md is the table `spatial-grounding bench` makes of results/bench.json."""
    result = json.loads((RESULTS / 'bench.json').read_text())
    assert (RESULTS / 'bench.md').read_text() == bench.table(result)
    assert [row['map'] for row in result['sizes']] == [f'{n}x{n}' for n in bench.SIZES]


# --- ShapeWorld ---------------------------------------------------------------------------


def shapeworld_results() -> dict:
    return json.loads((RESULTS / 'shapeworld.json').read_text())


def test_shapeworld_tables_are_the_json():
    """results/shapeworld.md and shapeworld_noise.md hold shapeworld.json's accuracies."""
    results = shapeworld_results()
    [table] = tables((RESULTS / 'shapeworld.md').read_text())
    rows = rows_by_header(table)
    assert [r['model'] for r in rows] == [r['model'] for r in results['runs']]
    for row, run in zip(rows, results['runs']):
        assert same_number(row['ACC ours'], run['test']['acc']), row['model']
        assert int(row['n']) == run['test']['n']
    [table] = tables((RESULTS / 'shapeworld_noise.md').read_text())
    noise = {(e['noise'], int(e['k']), e['model']): e['acc'] for e in results['noise']}
    cells = 0
    for row in rows_by_header(table):
        for header, cell in row.items():
            if header.endswith(' ACC'):
                model = header.removesuffix(' ACC')
                assert same_number(cell, noise[row['noise'], int(row['k']), model])
                cells += 1
    assert cells == len(noise)


def test_shapeworld_docs_page_shows_the_noise_table():
    """docs/shapeworld.md has results/shapeworld_noise.md's table, cell for cell."""
    [expected] = tables((RESULTS / 'shapeworld_noise.md').read_text())
    docs = (REPO / 'docs' / 'shapeworld.md').read_text()
    assert expected in tables(docs)
    assert '(docs/shapeworld.md)' in readme_section('Results')


def test_shapeworld_docs_page_figures_are_the_json():
    """docs/shapeworld.md's results table and the figures its prose states about it."""
    docs = (REPO / 'docs' / 'shapeworld.md').read_text()
    [expected] = tables((RESULTS / 'shapeworld.md').read_text())
    assert expected in tables(docs)
    results = shapeworld_results()
    rnet, vgg = ({r['model']: r for r in results['runs']}[m] for m in ('t-rnet-attn', 't-vgg'))
    noise = {(e['noise'], int(e['k']), e['model']): e['acc'] for e in results['noise']}
    checks = {
        '**Both meet the minimum: t-RNetAttn {} on the 500 test statements (paper {}; {} on the '
        'previous, all-plausible test split), t-VGG {} (paper {};': [
            rnet['test']['acc'], PAPER_ACC['t-rnet-attn'], rnet['test_plausible']['acc'],
            vgg['test']['acc'], PAPER_ACC['t-vgg'],
        ],
        't-RNetAttn trained in {} minutes ({} s;': [
            rnet['train_seconds'] / 60, rnet['train_seconds']
        ],
        't-VGG trained in {} minutes ({} s)': [vgg['train_seconds'] / 60, vgg['train_seconds']],
        'Its hard part is the absent object: {} on the statements without their subject and {} '
        'on the': [rnet['test']['by_reason'][r]['acc'] for r in ('subject', 'reference')],
        'against {} on the false-by-relation ones and {} on the true ones': [
            rnet['test']['by_reason'][r]['acc'] for r in ('relation', 'true')
        ],
        '{} and {} on the statements without their subject or reference, {} on the true ones, '
        'but {} on those false by their relation': [
            vgg['test']['by_reason'][r]['acc']
            for r in ('subject', 'reference', 'true', 'relation')
        ],
        'and {} on the all-plausible split, chance': [vgg['test_plausible']['acc']],
        '({} with one word, {} with ten)': [
            noise['text', k, 't-rnet-attn'] for k in (1, 10)
        ],
        't-VGG loses more to patches ({} to {} at k = 10': [
            noise['image', 0, 't-vgg'], noise['image', 10, 't-vgg']
        ],
        'less to words ({} at k = 10)': [noise['text', 10, 't-vgg']],
    }
    for sentence, values in checks.items():
        for figure, value in zip(said(docs, sentence), values, strict=True):
            assert same_number(figure, value), (sentence, figure, value)


@pytest.mark.parametrize('run', shapeworld_results()['runs'], ids=lambda r: r['model'])
def test_shipped_shapeworld_checkpoint_evaluates_to_its_row(run, tmp_path_factory, capsys):
    """
    `spatial-grounding eval` on the shipped checkpoint gives its results row.

    The test split is regenerated from its seed (into a fresh cache); another CPU's rounding can
    flip an example whose probability is a near-tie at 0.5: two such flips allowed.
    """
    cache = tmp_path_factory.mktemp('shapeworld_cache')
    name = run['checkpoint'].removesuffix('.pt')
    argv = ['shapeworld-eval', '--checkpoint', name, '--split', 'test', '--json']
    assert cli.main(argv + ['--cache', str(cache)]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got['model'] == run['model'] and got['n'] == run['test']['n']
    assert got['acc'] == pytest.approx(run['test']['acc'], abs=2 / run['test']['n'])


def test_robustness_table_is_the_json():
    """results/robustness.md is what robustness.markdown_table makes of robustness.json."""
    from spatial_grounding_ros.studies.robustness import robustness_markdown

    study = json.loads((RESULTS / 'robustness.json').read_text())
    assert (RESULTS / 'robustness.md').read_text() == robustness_markdown(study)


# --- the README's prose ---------------------------------------------------------------------
# The summary under the README's "## Results" states figures in sentences. Each check finds
# its sentence by its fixed words, reads the figures out of it and compares them with the
# results file at the precision the sentence writes them: a change that updates the results
# and the sentence together passes, a sentence left stale fails.

DEFAULT = 'pw_t-rnet-attn'


def said(text: str, sentence: str) -> list[str]:
    """
    Return the figures of `sentence` in `text`, where `sentence` marks each with `{}`.

    Line breaks and runs of spaces count as one space; a figure is a number, its % sign
    (if any) part of the sentence.
    """
    flat = ' '.join(text.split())
    pattern = r'(-?\d+(?:\.\d+)?)'.join(re.escape(part) for part in sentence.split('{}'))
    match = re.search(pattern, flat)
    assert match, f'the README no longer says: {sentence!r} (update this check with it)'
    return list(match.groups())


def same_percent(text: str, share: float) -> bool:
    """`text` (the number before a % sign) is `share` as a percentage at its precision."""
    return f'{share:.{len(text.partition(".")[2])}%}' == text + '%'


def readme_results() -> str:
    return readme_section('Results')


def check_prose(text: str) -> list[str]:
    """Return what the Results summary in `text` says that the results files do not."""
    wrong = []

    def compare(what, figures, values, same):
        for figure, value in zip(figures, values, strict=True):
            if not same(figure, value):
                wrong.append(f'{what}: the README says {figure}, the results {value!r}')

    # the reference suite, one map at a time (results/suite.json, make reproduce-suite)
    suite_run = json.loads((RESULTS / 'suite.json').read_text())['runs'][DEFAULT]
    figures = said(
        text,
        'the exact-goal rate (HIT) on the reference suite is {}% on 10x10 maps, {}% on 32x32 '
        'and {}% on 64x64',
    )
    sizes = ('10', '32', '64')
    hits = [suite_run['sizes'][s]['hit'] for s in sizes]
    compare('suite HIT at 10/32/64', figures, hits, same_percent)
    # the relations people use: the least of their families' rates at any size
    figures = said(text, 'the least of their rates at any size being {}%')
    least = min(suite_run['families'][f][s]['hit'] for f in RELATION_FAMILIES for s in sizes)
    compare('relations HIT, least', figures, [least], same_percent)
    # the same suite in the office table it never saw (results/landmarks.json, names, plain)
    [office] = [
        r
        for r in json.loads((RESULTS / 'landmarks.json').read_text())['runs'].values()
        if (r['checkpoint'], r['naming'], r['wording']) == (DEFAULT, 'name', 'plain')
        and not r.get('footprints')
    ]
    figures = said(text, 'with the landmarks of an office table it never saw, {}%, {}% and {}%')
    hits = [office['sizes'][s]['hit'] for s in sizes]
    compare('office suite HIT at 10/32/64', figures, hits, same_percent)
    # the model on the human test splits: the noise-free rows (k = 0) of results/robustness.json
    clean = {
        r['task']: r
        for r in json.loads((RESULTS / 'robustness.json').read_text())['results']
        if r['checkpoint'] == f'{DEFAULT}.pt' and r['k'] == 0
    }
    splits = ('pw-local', 'pw-global')
    figures = said(
        text,
        "On the human PuddleWorld test splits the model's MD is {} (local) and {} (global), "
        "against the paper's per-task {} and {}, and its HIT {} and {}",
    )
    compare('human splits MD', figures[0:2], [clean[s]['md'] for s in splits], same_number)
    paper = [TASKS[s].paper['t-rnet-attn'][2] for s in splits]
    compare("the paper's per-task MD", figures[2:4], paper, same_number)
    compare('human splits HIT', figures[4:6], [clean[s]['hit'] for s in splits], same_number)
    # through the Grounder: results/honesty.json
    honesty = json.loads((RESULTS / 'honesty.json').read_text())
    human = [honesty['human'][s] for s in splits]
    figures = said(
        text,
        'its best cell has MD {} and {} and HIT {} and {}, it declines {}% and {}% of them, the '
        'answers it gives land on the cell meant {}% and {}% of the time, and its confidence is '
        'calibrated to an expected error of {}',
    )
    compare('Grounder MD', figures[0:2], [h['md_best'] for h in human], same_number)
    compare('Grounder HIT', figures[2:4], [h['hit_best'] for h in human], same_number)
    compare('declined', figures[4:6], [h['declined'] for h in human], same_percent)
    compare('answers exact', figures[6:8], [h['hit_answered'] for h in human], same_percent)
    compare('calibration error', figures[8:9], [honesty['ece']['both']], same_number)
    # speed: results/bench.json (make bench)
    run = json.loads((RESULTS / 'bench.json').read_text())
    by_map = {row['map']: row for row in run['sizes']}
    figures = said(
        text,
        '`Grounder.ground` takes {}x it at 10x10 (target 5: met), {}x at 128x128 and {}x at '
        '512x512, and a 1024x1024 map {} ms in {} MB (in a process of its own)',
    )
    ratios = [by_map[m]['ground_over_yardstick'] for m in ('10x10', '128x128', '512x512')]
    compare('ground / yardstick', figures[0:3], ratios, same_number)
    # what the README says of each target is what the run found (met / missed)
    verdicts = {'ground_over_yardstick_10x10': True, 'ros_end_to_end_p50_ms': True,
                'ros_end_to_end_p99_ms': True}
    wrong += [f'README: {k} met is {run["checks"][k]["met"]}, it says {v}'
              for k, v in verdicts.items() if run['checks'][k]['met'] is not v]
    own = run['fresh_process']
    assert own['map'] == '1024x1024'
    compare('1024x1024', figures[3:5],
            [by_map['1024x1024']['ground_cached']['p50_ms'], own['peak_rss_mb']], same_number)
    figures = said(
        text,
        "the node's round trip for a new instruction, p50 {} and p99 {} ms (targets 2.5 and 5: "
        'met, met; and where the time goes), {} and {} ms for one it has grounded before and {} '
        'and {} ms for an echo node',
    )
    trips = [run[k][p] for k in ('ros_end_to_end', 'ros_end_to_end_repeated', 'ros_echo')
             for p in ('p50_ms', 'p99_ms')]
    compare('node round trip', figures, trips, same_number)
    # ShapeWorld: results/shapeworld.json (make reproduce-shapeworld)
    runs = {r['model']: r for r in shapeworld_results()['runs']}
    rnet, vgg = runs['t-rnet-attn'], runs['t-vgg']
    figures = said(
        text,
        't-RNetAttn reaches {} test accuracy (paper {}; {} on the previous, all-plausible test) '
        'in {} minutes; t-VGG,',
    )
    values = [rnet['test']['acc'], PAPER_ACC['t-rnet-attn'], rnet['test_plausible']['acc'],
              rnet['train_seconds'] / 60]
    compare('ShapeWorld t-RNetAttn', figures, values, same_number)
    figures = said(
        text, 'ImageNet features, {} (paper {}), but {} on the statements false by their relation'
    )
    values = [vgg['test']['acc'], PAPER_ACC['t-vgg'], vgg['test']['by_reason']['relation']['acc']]
    compare('ShapeWorld t-VGG', figures, values, same_number)
    return wrong


def test_value_maps_page_default_per_split_is_the_clean_robustness_rows():
    """docs/value-maps.md's table of the default on each human split: the k = 0 rows."""
    clean = {
        r['task']: r
        for r in json.loads((RESULTS / 'robustness.json').read_text())['results']
        if r['checkpoint'] == f'{DEFAULT}.pt' and r['k'] == 0
    }
    [table] = [
        t
        for t in tables((REPO / 'docs' / 'value-maps.md').read_text())
        if t[0] == ['split', 'MSE', 'PQ', 'MD', 'HIT']
    ]
    rows = rows_by_header(table)
    assert [r['split'] for r in rows] == ['PW local', 'PW global']
    for row, task in zip(rows, ('pw-local', 'pw-global')):
        for h in ('MSE', 'PQ', 'MD', 'HIT'):
            assert same_number(row[h], clean[task][h.lower()]), (task, h, row[h])


def test_readme_summary_figures_are_the_results_files():
    """The figures of the README's Results summary are those of results/*.json."""
    assert check_prose(readme_results()) == []


def test_a_stale_readme_summary_fails():
    """The check reads the figures: one changed figure in the sentence is one complaint."""
    text = readme_results()
    figure = said(text, 'the exact-goal rate (HIT) on the reference suite is {}% on 10x10')[0]
    stale = text.replace(f'reference suite is\n{figure}%', 'reference suite is\n12.3%').replace(
        f'reference suite is {figure}%', 'reference suite is 12.3%'
    )
    assert stale != text
    [complaint] = check_prose(stale)
    assert 'suite HIT' in complaint and '12.3' in complaint
