# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Why a model chose its goal: the paper's interpretability views (Figures 3 and 4), as a PNG.

The map, the predicted and true value maps, the relation map |Z1|, and for the cell pairs that
set the largest |Z1| the attention over the instruction's words.

    spatial-grounding explain --checkpoint pw-local_t-rnet-attn --task pw-local --index 0 \
        --out explain.png
    spatial-grounding explain --checkpoint pw_t-rnet-attn --map map.npy \
        --instruction 'reach cell to left of star' --out explain.png
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from .ground import read_grid
from .plots import plot_explanation
from ..core import world
from ..core.tasks import TASKS
from ..core.text import tokenize
from ..data.datasets import DEFAULT_DATA, load_task, SPLITS
from ..data.noise import add_noise, add_noise_options, NOISES, require_unseen_rows
from ..models.checkpoints import load_checkpoint, Loaded
from ..models.config import neighbour_offsets
from ..models.relation import cell_pairs
from ..models.trnet import TRNet

PAIRS_SHOWN = 3


@torch.no_grad()
def pair_scores(model: TRNet, grid: torch.Tensor, tokens: torch.Tensor):
    """
    Return every cell pair's relation score r_ij (N, P) and attention alpha_ij (N, P, L).

    For one map (1, H, W) and its instruction (1, L); attention is None for t-RNet. The forward
    keeps only Z1 = max_j r_ij and the attention averaged over all pairs; this evaluates the
    paper's formulas on the pairs of models.relation.cell_pairs with the model's own
    relations(), as its reference forward does:
    alpha_ij(k) ~ exp(h(k)^T A [phi(s_i); phi(s_j)]), r_ij = f_ij([phi(s_i); phi(s_j); l_ij]).
    """
    # (1, N, k), (1, N, P, k), from the map embedded with its off-map border
    phi_i, phi_j = cell_pairs(model.phi(grid), model.cfg.radius)
    r, attention = model.relations(phi_i, phi_j, model.text(tokens))
    return r[0], None if attention is None else attention[0]


def top_pairs(model, grid: np.ndarray, tokens: torch.Tensor, names, shown=PAIRS_SHOWN):
    """
    Return the pairs that set the largest Z1: for cell i, the neighbour j with the top r_ij.

    The largest, not the largest |Z1|: obstacles (puddles) score strongly negative for every
    instruction, so |Z1| ranks them first and says little about the words.

    A pair's score and attention depend only on the two kinds and their offset, so pairs that
    repeat an earlier (kind, kind, offset) are skipped: each pair shown says something new.
    names(kind) names a kind for the figure.
    """
    if not isinstance(model, TRNet):
        return []
    h, w = grid.shape
    r, attention = pair_scores(model, torch.from_numpy(grid[None]), tokens)
    best = r.argmax(dim=1)  # the neighbour that sets Z1 at each cell
    z1 = r.gather(1, best[:, None])[:, 0]
    radius = model.cfg.radius
    padded = np.pad(grid, radius, constant_values=model.phi.off_map)
    offsets = neighbour_offsets(radius)
    pairs, seen = [], set()
    for cell in torch.argsort(z1, descending=True).tolist():
        (row, col), p = divmod(cell, w), int(best[cell])
        nrow, ncol = row + offsets[p][0], col + offsets[p][1]
        kinds = (int(grid[row, col]), int(padded[nrow + radius, ncol + radius]))
        if (kinds, p) in seen:
            continue
        seen.add((kinds, p))
        pairs.append(
            {
                'cell': (row, col),
                'neighbour': (nrow, ncol),
                'names': [names(kind) for kind in kinds],
                'score': float(z1[cell]),
                'attention': None if attention is None else attention[cell, p].numpy(),
            }
        )
        if len(pairs) == shown:
            break
    return pairs


def explain(
    loaded: Loaded,
    out: str | Path,
    grid: np.ndarray,
    instruction: str,
    true_values: np.ndarray | None = None,
    true_goal=None,
    label: str = '',
) -> dict:
    """Write the explanation PNG of one grounding; return its goal cells and file."""
    entities, model = loaded.entities, loaded.model
    tokens = torch.from_numpy(loaded.vocab.encode_batch([instruction]))
    with torch.no_grad():
        values, aux = model(torch.from_numpy(grid[None]), tokens, return_aux=True)
    values = values[0].numpy()
    goal = tuple(int(x) for x in world.argmax_cells(values[None])[0])
    off_map = len(entities)

    def names(kind):
        if kind == off_map:
            return 'off map'
        return entities.names[kind] if kind < off_map else 'unseen'

    words = [w if w in loaded.vocab.index else f'{w}?' for w in tokenize(instruction)]
    unknown = any(w.endswith('?') for w in words)
    outcome = ''
    if true_goal is not None:
        distance = abs(goal[0] - true_goal[0]) + abs(goal[1] - true_goal[1])
        outcome = f' (goal {"hit" if distance == 0 else f"missed by {distance}"})'
    path = plot_explanation(
        out,
        grid,
        entities,
        f'{loaded.name}{label}: "{instruction}"{outcome}'
        + ('\n(? marks a word the model never saw)' if unknown else ''),
        values,
        aux['relation_map'][0].numpy(),
        goal,
        top_pairs(model, grid, tokens, names),
        words,
        true_values,
        true_goal,
    )
    return {'goal': goal, 'true_goal': true_goal, 'png': str(path)}


def read_map(path: str | Path, entities, unseen_kinds: int) -> np.ndarray:
    """Read an (H, W) grid of entity indices (ground.read_grid), checked against the table."""
    grid = read_grid(path)
    known = set(range(len(entities))) | set(
        range(len(entities) + 1, len(entities) + 1 + unseen_kinds)
    )
    bad = sorted(set(np.unique(grid).tolist()) - known)
    if bad:
        raise ValueError(
            f'{path}: values {bad} are not entity indices of the {entities.domain} table '
            f'(0..{len(entities) - 1}, unseen kinds {len(entities) + 1}..'
            f'{len(entities) + unseen_kinds})'
        )
    return grid.astype(np.int64)


def cmd_explain(args) -> int:
    noise = {name: getattr(args, name.replace('-', '_')) for name in NOISES}
    if not str(args.out).endswith('.png'):
        raise ValueError(f'--out must name a .png file, got {args.out}')
    if args.map is not None:
        if args.instruction is None:
            raise ValueError('--map needs --instruction')
        if any(noise.values()):
            raise ValueError('noise options need --task (a --map has no known goal)')
        loaded = load_checkpoint(args.checkpoint)
        grid = read_map(args.map, loaded.entities, loaded.model.cfg.unseen_kinds)
        result = explain(loaded, args.out, grid, args.instruction)
    else:
        if args.index is None:
            raise ValueError('--task needs --index (which example of the split)')
        if args.instruction is not None:
            raise ValueError("--instruction goes with --map; --task takes the example's own")
        data = load_task(args.task, args.split, args.data)
        if not 0 <= args.index < len(data):
            raise ValueError(
                f'--index {args.index} is out of range: {args.task} {args.split} has '
                f'{len(data)} examples (0..{len(data) - 1})'
            )
        loaded = load_checkpoint(args.checkpoint, expect_entities=data.entities)
        if noise['obs-noise']:
            require_unseen_rows(loaded.model, loaded.name)
        example = data.subset([args.index])
        for name, k in noise.items():
            example = add_noise(example, loaded.vocab, name, k, args.seed)
        added = ', '.join(f'{name} {k}' for name, k in noise.items() if k)
        result = explain(
            loaded,
            args.out,
            example.grids[0],
            example.instructions[0],
            example.values[0],
            tuple(int(x) for x in example.goals[0]),
            f' on {args.task} {args.split} #{args.index}' + (f' with {added}' if added else ''),
        )
    print(result['png'])
    return 0


def register_cli(sub) -> None:
    p = sub.add_parser(
        'explain', help='a PNG of a grounding: value maps, |Z1|, attention over the words'
    )
    p.add_argument('--checkpoint', required=True)
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument('--task', choices=TASKS, help='explain an example of a data set')
    source.add_argument(
        '--map', help='explain a map of your own: an (H, W) .npy file of entity indices'
    )
    p.add_argument('--split', default='test', choices=SPLITS)
    p.add_argument('--index', type=int, help='which example of the split (with --task)')
    p.add_argument('--instruction', help='the instruction (with --map)')
    p.add_argument('--data', default=DEFAULT_DATA)
    p.add_argument('--out', required=True, help='the PNG to write')
    add_noise_options(p)
    p.set_defaults(func=cmd_explain)
