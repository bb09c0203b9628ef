# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Data sets.

PuddleWorld (human instructions, the paper's split), ISI blocks, and a train/validation split by
world. All read from a path (`--data DIR`, default `DEFAULT_DATA`).

Every loader returns a `GroundingSet`: aligned arrays of grids, instructions, true value
maps, reward and terminal maps, and goal cells. The generator of our own PuddleWorld-style
worlds lives in `generator.py`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import gzip
import json
from pathlib import Path
import pickle

import numpy as np

from ..core import world
from ..core.entities import EntityTable, ISI, PUDDLEWORLD
from ..core.tasks import task as find_task

# Where the data sets are read from unless a command, node parameter or call says otherwise:
# the one place this path is written (the Makefile and config/gridworld.yaml take it from here).
DEFAULT_DATA = '../shared/data'
SPLITS = ('train', 'dev', 'test')

# The paper's test worlds (data README; they give 1566/399 local and 1071/272 global).
PW_TEST_WORLDS = {
    'local': {18, 20, 21, 22, 23, 24, 25, 26, 27, 30, 35, 40, 45, 46, 47, 49, 50, 53},
    'global': set(range(20, 40)) | set(range(60, 70)) | set(range(110, 120)),
}
ISI_GRID = 13


@dataclass
class GroundingSet:
    """
    Aligned examples.

    Grids (N,H,W) int64, values/rewards (N,H,W) float32, terminal (N,H,W) bool, goals (N,2) int64,
    one instruction and one world id per example.
    """

    name: str
    entities: EntityTable
    grids: np.ndarray
    instructions: list[str]
    values: np.ndarray
    rewards: np.ndarray
    terminal: np.ndarray
    goals: np.ndarray
    worlds: list[str] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.instructions)

    def subset(self, index, name: str | None = None) -> 'GroundingSet':
        index = np.asarray(index, dtype=np.int64)
        return GroundingSet(
            name or self.name,
            self.entities,
            self.grids[index],
            [self.instructions[i] for i in index],
            self.values[index],
            self.rewards[index],
            self.terminal[index],
            self.goals[index],
            [self.worlds[i] for i in index],
        )

    @staticmethod
    def concat(name: str, parts: list['GroundingSet']) -> 'GroundingSet':
        if len({p.grids.shape[1:] for p in parts}) != 1:
            raise ValueError('cannot concatenate data sets of different map sizes')
        return GroundingSet(
            name,
            parts[0].entities,
            np.concatenate([p.grids for p in parts]),
            [i for p in parts for i in p.instructions],
            np.concatenate([p.values for p in parts]),
            np.concatenate([p.rewards for p in parts]),
            np.concatenate([p.terminal for p in parts]),
            np.concatenate([p.goals for p in parts]),
            [w for p in parts for w in p.worlds],
        )


def _stack(name, entities, rows) -> GroundingSet:
    grids, instr, values, rewards, terminal, goals, worlds = zip(*rows)
    return GroundingSet(
        name,
        entities,
        np.stack(grids).astype(np.int64),
        list(instr),
        np.stack(values).astype(np.float32),
        np.stack(rewards).astype(np.float32),
        np.stack(terminal).astype(bool),
        np.array(goals, dtype=np.int64),
        list(worlds),
    )


def _load_pickle(path: Path):
    if not path.is_file():
        raise FileNotFoundError(
            f'{path}: data file not found (is --data the folder that holds puddleworld/ and isi/?)'
        )
    try:
        with open(path, 'rb') as f:
            return pickle.load(f, encoding='latin1')
    except Exception as exc:  # pickle raises many types on corrupt input
        raise ValueError(
            f'{path}: corrupt or unreadable pickle ({type(exc).__name__}: {exc})'
        ) from exc


def load_puddleworld(data_dir: str | Path, mode: str, split: str) -> GroundingSet:
    """
    Load PuddleWorld `mode` in {local, global} with human instructions, the paper's split.

    `split` is train or test (PuddleWorld has no dev split: carve one with `split_by_world`).
    """
    if mode not in PW_TEST_WORLDS:
        raise ValueError(f'unknown PuddleWorld mode {mode!r}; use local or global')
    if split not in ('train', 'test'):
        raise ValueError(
            f'PuddleWorld has splits train and test, not {split!r} '
            '(validation is carved out of train)'
        )
    root = Path(data_dir) / 'puddleworld'
    annotations = _load_pickle(root / f'{mode}.p')
    if not isinstance(annotations, dict):
        raise ValueError(f'{root / f"{mode}.p"}: expected a dict of annotations')
    worlds: dict[int, dict] = {}
    rows = []
    for key in sorted(annotations, key=lambda k: (int(k[0]), int(k[1]))):
        entry = annotations[key]
        if len(entry) != 5 or entry[4] != 'correct':
            continue
        actual = tuple(int(x) for x in entry[2])
        if actual != tuple(int(x) for x in entry[3]):
            continue
        number = int(key[0])
        if (number in PW_TEST_WORLDS[mode]) != (split == 'test'):
            continue
        if number not in worlds:
            worlds[number] = _load_pickle(root / mode / f'{number}.p')
        info = worlds[number]
        goals = [tuple(int(x) for x in g) for g in info['goals']]
        if actual not in goals:
            continue
        g = goals.index(actual)
        rows.append(
            (
                np.asarray(info['map']),
                str(entry[1]),
                np.asarray(info['values'][g]),
                np.asarray(info['rewards'][g]),
                np.asarray(info['terminal'][g]).astype(bool),
                actual,
                f'pw-{mode}/{number}',
            )
        )
    if not rows:
        raise ValueError(f'{root}: no PuddleWorld {mode} {split} examples found')
    return _stack(f'pw-{mode}-{split}', PUDDLEWORLD, rows)


def load_world_instructions(data_dir: str | Path, worlds: list[str]) -> GroundingSet:
    """
    Return the synthetic instructions stored in the world pickles.

    The synthetic instructions stored in the world pickles (`instructions`, one per goal,
    Janner et al.'s grammar), for the given PuddleWorld world ids (`pw-local/12`). Only ever
    pass training worlds: those of test worlds are a held-out benchmark of their own.
    """
    root = Path(data_dir) / 'puddleworld'
    rows = []
    for world_id in sorted(set(worlds), key=lambda w: (w.split('/')[0], int(w.split('/')[1]))):
        prefix, number = world_id.split('/')
        mode = prefix.removeprefix('pw-')
        if mode not in PW_TEST_WORLDS:
            raise ValueError(f'{world_id}: not a PuddleWorld world id (pw-local/N or pw-global/N)')
        if int(number) in PW_TEST_WORLDS[mode]:
            raise ValueError(f'{world_id} is a test world: its instructions are held out')
        info = _load_pickle(root / mode / f'{number}.p')
        for g, text in enumerate(info['instructions']):
            rows.append(
                (
                    np.asarray(info['map']),
                    str(text),
                    np.asarray(info['values'][g]),
                    np.asarray(info['rewards'][g]),
                    np.asarray(info['terminal'][g]).astype(bool),
                    tuple(int(x) for x in info['goals'][g]),
                    world_id,
                )
            )
    if not rows:
        raise ValueError(f'{root}: no world instructions found for {len(worlds)} worlds')
    return _stack('pw-world-instructions', PUDDLEWORLD, rows)


def pw_world_ids(
    data_dir: str | Path, modes: tuple[str, ...] = ('local', 'global'), split: str = 'train'
) -> list[str]:
    """Ids (`pw-local/12`) of every PuddleWorld world file of a split, annotated or not."""
    root = Path(data_dir) / 'puddleworld'
    ids = []
    for mode in modes:
        numbers = sorted(int(p.stem) for p in (root / mode).glob('*.p'))
        ids += [
            f'pw-{mode}/{n}' for n in numbers if (n in PW_TEST_WORLDS[mode]) == (split == 'test')
        ]
    return ids


def isi_cell(coord: float) -> int:
    """Return a board coordinate in [-1, 1] -> its cell 0..12 on the 13x13 grid (data README)."""
    return int(np.clip(np.floor((coord + 1.0) / 2.0 * ISI_GRID), 0, ISI_GRID - 1))


def layout_group(world: str) -> str:
    """
    Return the worlds that share a layout.

    An ISI world id is `isi-<split>/<sequence>/<step>` (load_isi), and the steps of a sequence
    share all but one block; any other world id is a layout of its own.
    """
    return world.rsplit('/', 1)[0] if world.startswith('isi-') else world


def load_isi(data_dir: str | Path, split: str) -> GroundingSet:
    """ISI blocks: every instruction of every A0 step of `{split}set.json.gz`."""
    if split not in SPLITS:
        raise ValueError(f'unknown split {split!r}; use one of {", ".join(SPLITS)}')
    path = Path(data_dir) / 'isi' / f'{split}set.json.gz'
    if not path.is_file():
        raise FileNotFoundError(f'{path}: data file not found')
    rows, pending = [], []  # pending: (grid, obstacles, goal, instructions, world)
    try:
        with gzip.open(path, 'rt', encoding='utf-8') as f:
            lines = f.readlines()
    except (OSError, EOFError, UnicodeDecodeError) as exc:
        raise ValueError(f'{path}: corrupt or truncated gzip file ({exc})') from exc
    for number, line in enumerate(lines):
        if not line.strip():
            continue
        try:
            seq = json.loads(line)
            states, offset = seq['states'], 1 if seq['decoration'] == 'logo' else 21
            for note in seq['notes']:
                if note['type'] != 'A0':
                    continue
                start, finish = states[note['start']], states[note['finish']]
                grid = np.zeros((ISI_GRID, ISI_GRID), dtype=np.int64)
                cells = [(isi_cell(p[2]), isi_cell(p[0])) for p in start]  # z is the row
                for block, cell in enumerate(cells):
                    grid[cell] = offset + block
                moved = int(
                    np.argmax([np.abs(np.subtract(a, b)).sum() for a, b in zip(start, finish)])
                )
                goal = (isi_cell(finish[moved][2]), isi_cell(finish[moved][0]))
                obstacles = grid > 0
                obstacles[cells[moved]] = False  # the moved block leaves its cell
                pending.append(
                    (
                        grid,
                        obstacles,
                        goal,
                        list(note['notes']),
                        f'isi-{split}/{number}/{note["start"]}',
                    )
                )
        except (KeyError, IndexError, TypeError, ValueError) as exc:
            raise ValueError(
                f'{path}: line {number + 1} is not an ISI board sequence ({exc!r})'
            ) from exc
    if not pending:
        raise ValueError(f'{path}: no A0 steps found')
    rewards, terminal = zip(*(world.reward_map(o, g) for _, o, g, _, _ in pending))
    values = world.value_iteration(np.stack(rewards), np.stack(terminal))
    for (grid, _, goal, notes, wid), v, r, t in zip(pending, values, rewards, terminal):
        for text in notes:
            rows.append((grid, str(text), v, r, t, goal, wid))
    return _stack(f'isi-{split}', ISI, rows)


def load_task(task: str, split: str, data_dir: str | Path) -> GroundingSet:
    """Return a task's split: pw-local, pw-global, pw (both, 10x10) or isi."""
    found = find_task(task)
    if found.data == 'isi':
        return load_isi(data_dir, split)
    if split == 'dev':
        raise ValueError(
            'PuddleWorld has no dev split: the validation split is carved out of train'
        )
    parts = [load_puddleworld(data_dir, mode, split) for mode in found.pw_modes]
    return parts[0] if len(parts) == 1 else GroundingSet.concat(f'{task}-{split}', parts)


def split_by_world(
    data: GroundingSet, fraction: float, seed: int
) -> tuple[GroundingSet, GroundingSet]:
    """
    Hold out `fraction` of the worlds for validation.

    Hold out `fraction` of the worlds (every instruction of a world goes to one side), so
    validation never sees a training map: worlds that share a layout (an ISI sequence) go
    to one side together.
    """
    groups = [layout_group(w) for w in data.worlds]
    names = sorted(set(groups))
    rng = np.random.default_rng(seed)
    held = set(rng.choice(names, size=max(1, int(round(len(names) * fraction))), replace=False))
    mask = np.array([g in held for g in groups])
    return (
        data.subset(np.flatnonzero(~mask), data.name + '-train'),
        data.subset(np.flatnonzero(mask), data.name + '-val'),
    )
