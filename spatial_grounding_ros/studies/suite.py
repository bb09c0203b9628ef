# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The reference suite.

Does a model send the robot to the cell a clear instruction names?

Generated worlds at each size, every relation family of the generator (Janner et al.'s
synthetic grammar; with `--families`, also the relations the network did not learn,
RELATION_FAMILIES, the 'relations' group) in equal numbers; per family and size, HIT (the
share of maps whose predicted argmax is the named cell) and MD (Manhattan distance to it).
Each map is grounded alone through Grounder.ground, the node's own path, so the rates are the
node's. Only the goal
cell matters here, so no value iteration is run: the suite is cheap at 64x64.

    spatial-grounding suite --checkpoint pw_t-rnet-attn --sizes 10 32 64 --n 100 --json
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import NamedTuple

import numpy as np
from tqdm import tqdm

from ..core.entities import EntityTable, PUDDLEWORLD
from ..data.footprints import grow, separate, unexplored
from ..data.generator import (
    COMPOSITIONAL_FAMILIES,
    FAMILIES,
    GLOBAL_FAMILIES,
    LOCAL_FAMILIES,
    RELATION_FAMILIES,
    sample,
)
from ..data.paraphrase import in_metres, paraphrase
from ..data.renaming import NAMINGS, rename
from ..grounder import DEFAULT_MIN_CONFIDENCE, Grounder, resolve_table
from ..models.checkpoints import load_checkpoint
from ..training.options import ranged

GROUPS = {
    'local': LOCAL_FAMILIES,
    'global': GLOBAL_FAMILIES,
    'compositional': COMPOSITIONAL_FAMILIES,
    'relations': RELATION_FAMILIES,
}
# every family the suite can run; a family's seed is its index here, so that the relation
# families (appended) leave the seeds of FAMILIES' worlds as they were
SUITE_FAMILIES = FAMILIES + RELATION_FAMILIES
DEFAULT_SIZES = (10, 32, 64)
WORDINGS = ('plain', 'paraphrase', 'metric')


class SuiteWorld(NamedTuple):
    """One suite case: a map, an instruction, the cell it names and the map's cell size."""

    grid: np.ndarray
    instruction: str
    goal: tuple[int, int]
    cell_size: float | None = None  # metres per cell, for instructions in metres


def suite_worlds(
    family: str,
    size: int,
    n: int,
    seed: int,
    table: EntityTable = PUDDLEWORLD,
    naming: str = 'name',
    wording: str = 'plain',
    footprints: bool = False,
):
    """
    Return n SuiteWorlds of one family and size; the same for every model.

    In another `table`, the same layouts and goals with its kinds, named by `naming`
    (data/renaming.py: the name, an alias, or a typo of the name); with `wording`
    'paraphrase', the instructions worded as people word them, with 'metric' each count of
    cells said in metres at a cell size drawn per world (data/paraphrase.py). In a
    table whose landmarks have footprints, touching landmarks of a kind are one, so each
    such group keeps one cell; `footprints` draws the landmarks over several cells and
    leaves regions unexplored (data/footprints.py).
    """
    if wording not in WORDINGS:
        raise ValueError(f'unknown wording {wording!r}; use one of {", ".join(WORDINGS)}')
    rng = np.random.default_rng([seed, size, SUITE_FAMILIES.index(family)])
    renamer = np.random.default_rng([seed, size, SUITE_FAMILIES.index(family), 1])
    renamed = table.names != PUDDLEWORLD.names or naming != 'name'
    worlds = []
    for _ in range(100 * n):
        grid, text, goal = sample(rng, family, size)
        if renamed:
            grid, text = rename(grid, text, table, renamer, naming)
        # a clear instruction never names a cell a robot cannot stop on: a landmark renamed
        # into solid furniture on the goal of an offset makes it an unanswerable case
        # (goal-on-obstacle); sent to the landmark itself, the robot stops beside it
        if family == 'referent' or int(grid[goal]) not in table.never_goal:
            worlds.append((grid, text, goal))
        if len(worlds) == n:
            break
    else:
        raise ValueError(f'the {table.domain} table leaves too few clear {family} worlds')
    if table.has_footprints:
        worlds = [(separate(g, t, goal, table), t, goal) for g, t, goal in worlds]
    if footprints:
        if not table.has_footprints:
            raise ValueError(f'the {table.domain} table draws every landmark over one cell')
        drawer = np.random.default_rng([seed, size, SUITE_FAMILIES.index(family), 3])
        worlds = [
            (unexplored(grow(g, t, goal, table, drawer), goal, table, drawer), t, goal)
            for g, t, goal in worlds
        ]
    worlds = [SuiteWorld(g, t, goal) for g, t, goal in worlds]
    if wording == 'paraphrase':
        words = np.random.default_rng([seed, size, SUITE_FAMILIES.index(family), 2])
        names = {w for n in table.names for w in n.split('_')}
        worlds = [w._replace(instruction=paraphrase(w.instruction, words, names)) for w in worlds]
    elif wording == 'metric':
        words = np.random.default_rng([seed, size, SUITE_FAMILIES.index(family), 2])
        worlds = [
            w._replace(**dict(zip(('instruction', 'cell_size'), in_metres(w.instruction, words))))
            for w in worlds
        ]
    return worlds


def _summary(distances: list[int]) -> dict:
    """
    Hit, MD and the share declined, of distances from the best cell to the named one.

    A declined grounding's distance is stored negative (-1 - d): it sends no goal, so it is no
    hit, and its MD is its best cell's.
    """
    raw = np.asarray(distances)
    d = np.where(raw < 0, -1 - raw, raw)
    return {
        'hit': float(np.mean(raw == 0)) if len(d) else None,
        'md': float(np.mean(d)) if len(d) else None,
        'declined': float(np.mean(raw < 0)) if len(d) else None,
        'n': int(len(d)),
    }


def run_suite(
    checkpoint,
    sizes=DEFAULT_SIZES,
    n: int = 100,
    seed: int = 0,
    families=FAMILIES,
    out: str | Path | None = None,
    failures_shown: int = 6,
    progress: bool = True,
    entities: str | Path | EntityTable | None = None,
    naming: str = 'name',
    wording: str = 'plain',
    footprints: bool = False,
    kinds_by: str = 'name',
) -> dict:
    """
    Hit and MD per family and size, per group and size, per size, and overall.

    `entities`: a table of one's own (a YAML path): the worlds are renamed into it
    (suite_worlds) and grounded with it.
    """
    if not sizes or min(sizes) < 5:
        raise ValueError(
            f"suite sizes must be >= 5 (the generator's smallest world), got {list(sizes)}"
        )
    if n < 1:
        raise ValueError(f'--n must be at least 1, got {n}')
    loaded = load_checkpoint(checkpoint, expect_entities=PUDDLEWORLD)
    table = resolve_table(entities) or PUDDLEWORLD
    # a checkpoint never calibrated has a confidence that means little (T = 1): it grounds
    # at min_confidence 0, as the node's users of such checkpoints are told to
    calibrated = 'calibration' in loaded.header
    grounder = Grounder(
        loaded, table, min_confidence=DEFAULT_MIN_CONFIDENCE if calibrated else 0.0,
        kinds_by=kinds_by,
    )
    distances = {f: {} for f in families}
    failures = {f: [] for f in families}
    jobs = [(f, s) for s in sizes for f in families]
    for family, size in tqdm(jobs, desc='suite', disable=not progress, unit='family'):
        worlds = suite_worlds(family, size, n, seed, table, naming, wording, footprints)
        grids = np.stack([w.grid for w in worlds])
        texts = [w.instruction for w in worlds]
        goals = np.array([w.goal for w in worlds])
        groundings = [grounder.ground(w.grid, w.instruction, w.cell_size) for w in worlds]
        maps = np.stack([g.values for g in groundings])
        pred = np.array([g.best for g in groundings])
        d = np.abs(pred - goals).sum(1)
        declined = np.array([g.goal is None for g in groundings])
        distances[family][size] = np.where(declined, -1 - d, d).tolist()
        for i in np.flatnonzero(d | declined)[:failures_shown]:
            failures[family].append(
                (size, grids[i], texts[i], tuple(goals[i]), tuple(pred[i]), maps[i])
            )
    result = {
        'checkpoint': str(checkpoint),
        'entities': table.domain,
        'naming': naming,
        'wording': wording,
        'footprints': footprints,
        'model': loaded.name,
        'seed': seed,
        'n_per_family': n,
        'sizes': {},
        'groups': {},
        'families': {},
    }
    for family in families:
        result['families'][family] = {str(s): _summary(distances[family][s]) for s in sizes}
    for group, members in GROUPS.items():
        members = [f for f in members if f in families]
        if members:
            result['groups'][group] = {
                str(s): _summary([x for f in members for x in distances[f][s]]) for s in sizes
            }
    for s in sizes:
        result['sizes'][str(s)] = _summary([x for f in families for x in distances[f][s]])
    result.update(_summary([x for f in families for s in sizes for x in distances[f][s]]))
    if out is not None:
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        (out / 'suite.json').write_text(json.dumps(result, indent=1) + '\n')
        result['failure_plots'] = [str(p) for p in plot_failures(out, failures, table)]
    return result


def plot_failures(out: Path, failures: dict, table: EntityTable = PUDDLEWORLD) -> list[Path]:
    """
    One PNG per family with failures.

    Each row a map (instruction above it), the true goal (green circle) and the model's choice (red
    x) on the map and on the value map.
    """
    from .plots import plt

    paths = []
    for family, cases in failures.items():
        if not cases:
            continue
        fig, axes = plt.subplots(len(cases), 2, figsize=(8, 4 * len(cases)), squeeze=False)
        for (size, grid, text, goal, pred, values), (ax_map, ax_val) in zip(cases, axes):
            draw_case(ax_map, ax_val, grid, table, values, goal, pred, labels=size <= 32)
            ax_map.set_title(f'{size}x{size}: {text}', fontsize=8, loc='left')
        fig.suptitle(f"{family}: failures (green o = named cell, red x = model's goal)")
        fig.tight_layout()
        path = out / f'failures_{family}.png'
        fig.savefig(path, dpi=70)
        plt.close(fig)
        paths.append(path)
    return paths


def markdown_table(results: dict[str, dict]) -> str:
    """Hit per family and size, one column per checkpoint (results: name -> run_suite())."""
    names = list(results)
    first = results[names[0]]
    sizes = list(first['sizes'])
    lines = [
        '| family | size | ' + ' | '.join(names) + ' |',
        '| --- | --- | ' + ' | '.join('---' for _ in names) + ' |',
    ]
    families = dict.fromkeys(f for r in results.values() for f in r['families'])
    for family in families:
        for s in sizes:
            cells = [
                f'{r["families"][family][s]["hit"]:.1%}' if family in r['families'] else '-'
                for r in results.values()
            ]
            lines.append(f'| {family} | {s} | ' + ' | '.join(cells) + ' |')
    for s in sizes:
        cells = [
            f'**{r["sizes"][s]["hit"]:.1%}** (MD {r["sizes"][s]["md"]:.2f})'
            for r in results.values()
        ]
        lines.append(f'| **all** | {s} | ' + ' | '.join(cells) + ' |')
    return '\n'.join(lines) + '\n'


def draw_case(ax_map, ax_val, grid, table, values, goal, pred, labels=True) -> None:
    """
    Draw a map (obstacles shaded, landmarks named) and its value map.

    On both: the cell named (green o) and the goal (red x; none when the grounding declines).
    """
    ax_map.imshow(np.isin(grid, table.obstacles), cmap='Blues', vmin=0, vmax=2)
    if labels:
        for (r, c), e in np.ndenumerate(grid):
            if e not in table.obstacles and e != table.free_kind:
                ax_map.text(c, r, table.names[e][:4], ha='center', va='center',
                            fontsize=max(3, min(7, 70 // grid.shape[0])))
    ax_val.imshow(values, cmap='viridis')
    for ax in (ax_map, ax_val):
        ax.plot(goal[1], goal[0], 'o', mfc='none', mec='lime', ms=12, mew=2)
        if pred is not None:
            ax.plot(pred[1], pred[0], 'x', color='red', ms=10, mew=2)
        ax.set_xticks([])
        ax.set_yticks([])


def plot_examples(out: str | Path, families, checkpoint='pw_t-rnet-attn', per_family: int = 2,
                  seed: int = 0) -> list[Path]:
    """
    One PNG per family: `per_family` of its 10x10 suite worlds grounded, as a user sees them.

    Each row the map (its landmarks named), the instruction, the named cell (green circle) and
    the grounder's goal (red x; none when it declines), and the value map behind the goal.
    """
    from .plots import plt

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    grounder = Grounder.from_checkpoint(checkpoint)
    table, paths = grounder.entities, []
    for family in families:
        worlds = suite_worlds(family, 10, per_family, seed)
        fig, axes = plt.subplots(per_family, 2, figsize=(7, 3.6 * per_family), squeeze=False)
        for w, (ax_map, ax_val) in zip(worlds, axes):
            g = grounder.ground(w.grid, w.instruction, w.cell_size)
            draw_case(ax_map, ax_val, w.grid, table, g.values, w.goal, g.goal)
            said = f'"{w.instruction}"'
            ax_map.set_title(said if len(said) < 48 else said[:46] + '...', fontsize=8, loc='left')
            ax_val.set_title(f'value map, confidence {g.confidence:.2f}', fontsize=8, loc='left')
        fig.suptitle(f'{family}: green o = the cell named, red x = the goal sent', fontsize=9)
        fig.tight_layout()
        path = out / f'{family}.png'
        fig.savefig(path, dpi=70)
        plt.close(fig)
        paths.append(path)
    return paths


def cmd_suite(args) -> int:
    if args.examples:
        for path in plot_examples(args.examples, args.families, args.checkpoint):
            print(f'wrote {path}')
        return 0
    result = run_suite(
        args.checkpoint,
        tuple(args.sizes),
        args.n,
        args.seed,
        tuple(args.families),
        args.out,
        progress=not args.json,
        entities=args.entities,
        naming=args.naming,
        wording=args.wording,
        footprints=args.footprints,
    )
    if args.json:
        print(json.dumps(result))
        return 0
    print(
        f'{result["model"]} ({args.checkpoint}), {args.n} worlds per family and size, '
        f'seed {args.seed}, {result["entities"]} table, landmarks named by {args.naming}'
    )
    print(f'{"family":16s}' + ''.join(f'{s:>16s}' for s in result['sizes']))
    for family, per_size in result['families'].items():
        print(
            f'{family:16s}'
            + ''.join(f'{v["hit"]:>9.1%} MD{v["md"]:4.2f}' for v in per_size.values())
        )
    print(
        f'{"all":16s}'
        + ''.join(f'{v["hit"]:>9.1%} MD{v["md"]:4.2f}' for v in result['sizes'].values())
    )
    if args.out:
        print(
            f'wrote {Path(args.out) / "suite.json"} and '
            f'{len(result["failure_plots"])} failure PNGs'
        )
    return 0


def register_cli(sub) -> None:
    p = sub.add_parser('suite', help='exact-goal rate per relation family on generated worlds')
    p.add_argument('--checkpoint', default='pw_t-rnet-attn')
    p.add_argument('--sizes', type=ranged(int, low=5), nargs='+', default=list(DEFAULT_SIZES))
    p.add_argument('--n', type=ranged(int, low=1), default=100, help='worlds per family and size')
    p.add_argument('--seed', type=ranged(int, low=0), default=0)
    p.add_argument(
        '--families', nargs='+', default=list(SUITE_FAMILIES), choices=SUITE_FAMILIES,
        help='the families to run (default: all, the ones the network learned whole and the '
        'relations composed from its groundings)',
    )
    p.add_argument(
        '--entities',
        default=None,
        help='an entity table of your own (YAML): the worlds are renamed into its kinds',
    )
    p.add_argument(
        '--naming',
        default='name',
        choices=NAMINGS,
        help="how instructions name the landmarks: the table's names, its aliases, or a "
        'one-letter typo of the names',
    )
    p.add_argument(
        '--wording',
        default='plain',
        choices=WORDINGS,
        help="the generator's grammar, or paraphrased as people word it (data/paraphrase.py)",
    )
    p.add_argument(
        '--footprints',
        action='store_true',
        help='landmarks drawn over several cells and unexplored regions, as a robot map '
        'draws them (needs --entities with a table whose landmarks have footprints)',
    )
    p.add_argument('--json', action='store_true', help='print exactly one JSON object')
    p.add_argument('--out', default=None, help='write suite.json and failure PNGs here')
    p.add_argument(
        '--examples', default=None, metavar='DIR',
        help='instead, write one PNG per family of two 10x10 worlds grounded, into DIR',
    )
    p.set_defaults(func=cmd_suite)
