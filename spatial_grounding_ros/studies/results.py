# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Results files that several runs add rows to: results/value_map.json and results/rl.json.

A run replaces its own (task, model) rows and keeps everyone else's. Runs in parallel processes
(one per task, or two `reproduce-rl` at once) may share a file, so each read-modify-write holds an
exclusive lock on `<file>.lock`, and the file is replaced whole, never left half-written.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
from pathlib import Path
from typing import Callable

from ..core.tasks import TASKS


PACKAGE = 'spatial_grounding_ros'
EXCLUDED = f':(exclude){PACKAGE}/checkpoints'


def code_version() -> str:
    """
    Return the commit the package runs from ('<hash>-dirty' with changes not committed).

    'unknown' outside a git checkout (an installed wheel): a results row says which code made it.
    """
    import subprocess

    root = Path(__file__).resolve().parents[2]  # the package's checkout
    try:
        commit = subprocess.run(
            ['git', 'rev-parse', '--short', 'HEAD'],
            cwd=root,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
        dirty = subprocess.run(
            # a run's own checkpoints, copied into the package as it goes, are no change
            ['git', 'status', '--porcelain', '--untracked-files=no', '--', PACKAGE, EXCLUDED],
            cwd=root,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return 'unknown'
    return f'{commit}-dirty' if dirty else commit


@contextlib.contextmanager
def locked(path: Path):
    """Hold an exclusive lock on `path`'s `.lock` file (other processes wait for it)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path.with_suffix('.lock'), 'w') as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        yield


def write_atomically(path: Path, text: str) -> None:
    """Write `text` to a temporary file beside `path`, then rename it over `path`."""
    tmp = path.with_name(f'.{path.name}.{os.getpid()}.tmp')
    tmp.write_text(text)
    os.replace(tmp, path)


def merge_rows(
    path: str | Path,
    rows: list[dict],
    key: str,
    head: dict,
    table: Callable[[list[dict]], str] | None = None,
) -> list[dict]:
    """
    Add `rows` to the list `key` of JSON file `path`, replacing rows of the same (task, model).

    The file becomes `{**head, key: merged rows}`, rows in task order (tasks.TASKS, other
    tasks last) then by model; with `table`, `path`'s `.md` sibling becomes `table(merged)`.
    Returns the merged rows.
    """
    path = Path(path)
    order = {t: i for i, t in enumerate(TASKS)}
    with locked(path):
        earlier = json.loads(path.read_text())[key] if path.is_file() else []
        merged = {(r['task'], r['model']): r for r in [*earlier, *rows]}
        merged = sorted(
            merged.values(), key=lambda r: (order.get(r['task'], len(order)), r['model'])
        )
        write_atomically(path, json.dumps({**head, key: merged}, indent=1) + '\n')
        if table is not None:
            write_atomically(path.with_suffix('.md'), table(merged))
    return merged
