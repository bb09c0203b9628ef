# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Ground one instruction on a map of one's own from the command line, and draw it.

    spatial-grounding ground --entities config/entities_office.yaml --map office.txt
        --instruction "go two cells below the couch" --out couch.png

The map is a text file of entity indices (one row per line, row 0 north) or an (H, W)
.npy; the answer is printed (goal, confidence, reason, alternatives) and, with --out, drawn:
the map with its landmarks' names, the value map, the goal (or the best cell of a declined
grounding) and the next best cells.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..core.footprints import footprints
from ..grounder import Grounder, Grounding
from ..language.checks import said
from ..training.options import ranged


def read_grid(path: str | Path) -> np.ndarray:
    """Return an (H, W) int grid from a .npy file or a text file of whitespace-separated ints."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f'{path}: map file not found')
    if path.suffix == '.npy':
        try:
            grid = np.load(path, allow_pickle=False)
        except (OSError, ValueError) as exc:
            raise ValueError(f'{path}: not a .npy array ({exc})') from exc
    else:
        rows = [line.split() for line in path.read_text().splitlines() if line.strip()]
        if not rows or len({len(r) for r in rows}) != 1:
            raise ValueError(f'{path}: a text map needs rows of equal length')
        try:
            grid = np.array(rows, dtype=np.int64)
        except ValueError as exc:
            raise ValueError(f'{path}: a text map holds whole numbers only ({exc})') from exc
    if grid.ndim != 2 or grid.size == 0 or not np.issubdtype(grid.dtype, np.integer):
        raise ValueError(
            f'{path}: a map is a 2-D integer array of entity indices, '
            f'got {grid.dtype} {grid.shape}'
        )
    return grid.astype(np.int64)


def summary(g: Grounding) -> dict:
    """Return what a grounding answers, as plain data."""
    return {
        'instruction': g.instruction,
        'goal': g.goal,
        'best': g.best,
        'confidence': round(g.confidence, 4),
        'reason': g.reason,
        'alternatives': [[list(c), round(p, 4)] for c, p in g.alternatives],
        'landmarks': g.landmarks,
        'unknown_words': g.unknown_words,
        'model_instruction': g.model_instruction,
        # what the instruction asks (go, stop, question, sequence, ...); a sequence's steps'
        # goals in order; a question's answer
        'intent': g.intent,
        'steps': [None if s.goal is None else list(s.goal) for s in g.steps],
        'answer': g.answer,
    }


def draw(grid: np.ndarray, grounder: Grounder, g: Grounding, path: str | Path) -> Path:
    """Draw the map with its landmarks' names beside the value map, with the goal marked."""
    from .plots import plt

    table = grounder.entities
    fig, (ax_map, ax_val) = plt.subplots(1, 2, figsize=(10, 5))
    ax_map.imshow(np.isin(grid, table.obstacles), cmap='Greys', vmin=0, vmax=1.5)
    label_landmarks(ax_map, grid, table)
    ax_val.imshow(g.values, cmap='viridis')
    for ax in (ax_map, ax_val):
        for (r, c), _ in g.alternatives:
            ax.plot(c, r, '+', color='orange', ms=9, mew=2)
        marker = {'color': 'red' if g.goal else 'grey', 'ms': 14, 'mew': 3 if g.goal else 2}
        ax.plot(g.best[1], g.best[0], 'x', **marker)
        ax.set_xticks([])
        ax.set_yticks([])
    verdict = (
        f'goal {g.goal}, confidence {g.confidence:.2f}'
        if g.goal
        else f'declined: {g.reason} (best cell {g.best}, grey)'
    )
    ax_map.set_title(f'{g.instruction}\n{verdict}', fontsize=9, loc='left')
    ax_val.set_title('value map (red x: goal; orange +: next best)', fontsize=9, loc='left')
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path


def label_landmarks(ax, grid: np.ndarray, table) -> None:
    """
    Mark each landmark's cells and write its name once, by its middle.

    A name goes under the landmark, else over it, else further off, wherever it covers no
    name written before (adjacent landmarks' names overlapped).
    """
    renderer = ax.figure.canvas.get_renderer()
    placed = []
    for kind in np.unique(grid):
        if kind == table.free_kind or kind in table.obstacles:
            continue
        for cells in footprints(grid, int(kind)):
            ax.plot(cells[:, 1], cells[:, 0], 's', color='tab:blue', ms=5, ls='')
            r, c = cells.mean(0)
            low, high = cells[:, 0].max() + 0.3, cells[:, 0].min() - 0.3
            # under, over, further under, further over; the last one stays if all overlap
            spots = ((low, 'top'), (high, 'bottom'), (low + 0.6, 'top'), (high - 0.6, 'bottom'))
            for k, (y, va) in enumerate(spots):
                text = ax.text(c, y, said(table, kind), ha='center', va=va, fontsize=7)
                box = text.get_window_extent(renderer)
                if k == len(spots) - 1 or not any(box.overlaps(other) for other in placed):
                    break
                text.remove()
            placed.append(box)


def cmd_ground(args) -> int:
    grounder = Grounder.from_checkpoint(
        args.checkpoint, args.entities, args.min_confidence, cell_size=args.cell_size
    )
    grid = read_grid(args.map)
    g = grounder.ground(grid, args.instruction)
    result = summary(g)
    if args.out:
        result['png'] = str(draw(grid, grounder, g, args.out))
    print(json.dumps(result, indent=None if args.json else 1))
    return 0


def register_cli(sub) -> None:
    p = sub.add_parser('ground', help='ground one instruction on a map of your own (and draw it)')
    p.add_argument('--checkpoint', default='pw_t-rnet-attn')
    p.add_argument(
        '--entities', default=None, help="your entity table (YAML); default: the checkpoint's"
    )
    p.add_argument('--map', required=True, help='a text file of entity indices, or a .npy')
    p.add_argument('--instruction', required=True)
    p.add_argument('--min-confidence', type=ranged(float, low=0.0, high=1.0), default=0.0)
    p.add_argument(
        '--cell-size',
        type=ranged(float, low=1e-6),
        default=None,
        help='metres per cell, for distances in metres ("two metres south of the sofa")',
    )
    p.add_argument('--out', default=None, help='draw the grounding into this PNG')
    p.add_argument('--json', action='store_true', help='print exactly one line of JSON')
    p.set_defaults(func=cmd_ground)
