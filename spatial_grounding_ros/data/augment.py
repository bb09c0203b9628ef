# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Mirror and distractor augmentation.

A map flipped left-right (or top-bottom), with the direction words of its instruction swapped, is
another correct example: the grid MDP is symmetric under both flips, so the flipped value map is
exactly the value map of the flipped world.

Human instructions use many spellings; the tables below cover every direction word that
occurs at least twice in PuddleWorld or ISI train (misspellings map to the right opposite). A
word the tables miss leaves that mirrored example mislabeled, so the tables err on
completeness. Some direction words also have non-directional uses ("pick up", "right next
to"); NOT_DIRECTIONS keeps those as they are.
"""

from __future__ import annotations

import numpy as np
import torch

from .datasets import GroundingSet
from .noise import ARTICLES, free_cells, VERBS
from ..core.tasks import NOISE_SHARE
from ..core.text import PAD, tokenize, UNK, Vocabulary


def _pairs(*pairs: tuple[str, str]) -> dict[str, str]:
    table = {}
    for a, b in pairs:
        table.setdefault(a, b)
        table.setdefault(b, a)
    return table


# Mirror columns: west <-> east. Misspellings map to the correct opposite.
SWAP_LEFT_RIGHT = _pairs(
    ('left', 'right'),
    ('leftmost', 'rightmost'),
    ('west', 'east'),
    ('western', 'eastern'),
    ('westernmost', 'easternmost'),
    ('westmost', 'eastmost'),
    ('eastermost', 'westernmost'),
    ('eaternmost', 'westernmost'),
    ('northwest', 'northeast'),
    ('southwest', 'southeast'),
    ('northwestern', 'northeastern'),
    ('southwestern', 'southeastern'),
    ('northwesternmost', 'northeasternmost'),
    ('southwesternmost', 'southeasternmost'),
    ('lefthand', 'righthand'),
    ('westward', 'eastward'),
    ('westermost', 'easternmost'),
    ('eastenmost', 'westernmost'),
    ('mosteastern', 'mostwestern'),
    ('topright', 'topleft'),
    ('bottomright', 'bottomleft'),
)
# Mirror rows: north <-> south.
SWAP_UP_DOWN = _pairs(
    ('above', 'below'),
    ('up', 'down'),
    ('top', 'bottom'),
    ('topmost', 'bottommost'),
    ('upper', 'lower'),
    ('uppermost', 'lowermost'),
    ('highest', 'lowest'),
    ('higher', 'lower'),
    ('north', 'south'),
    ('northern', 'southern'),
    ('northernmost', 'southernmost'),
    ('northmost', 'southmost'),
    ('upmost', 'downmost'),
    ('over', 'under'),
    ('bellow', 'above'),
    ('beneath', 'above'),
    ('underneath', 'above'),
    ('bottomost', 'topmost'),
    ('southernest', 'northernmost'),
    ('northwest', 'southwest'),
    ('northeast', 'southeast'),
    ('northwestern', 'southwestern'),
    ('northeastern', 'southeastern'),
    ('northeasternmost', 'southeasternmost'),
    ('northwesternmost', 'southwesternmost'),
    ('low', 'high'),
    ('northest', 'southernmost'),
    ('southermost', 'northernmost'),
    ('underneeth', 'above'),
    ('topright', 'bottomright'),
    ('topleft', 'bottomleft'),
    ('upward', 'downward'),
    ('upwards', 'downwards'),
    ('tops', 'bottoms'),
    ('atop', 'below'),
    ('ontop', 'below'),
    ('blow', 'above'),
    ('belows', 'above'),
)

# Uses of direction words that are not directions, so no flip changes them: the word keeps
# its spelling after any of its `after` words, or before any of its `before` words or word
# pairs. ISI blocks are "picked up", "lined up with" others and put "right next to" them.
# "right above" stays a direction: PuddleWorld's "one to the right below the tree" is one.
NOT_DIRECTIONS = {
    'up': {
        'after': {
            'pick',
            'picks',
            'picked',
            'picking',
            'line',
            'lines',
            'lined',
            'lining',
            'match',
            'matches',
            'matched',
            'end',
            'ends',
            'ended',
        },
        'before': set(),
    },
    'right': {
        'after': set(),
        'before': {
            'next',
            'on top',
            'beside',
            'besides',
            'in',
            'at',
            'between',
            'against',
            'behind',
            'alongside',
            'atop',
            'near',
            'by',
            'where',
            'there',
            'here',
            'now',
            'adjacent',
            'touching',
            'directly',
            'immediately',
        },
    },
}


# The word table of a flip of an (H, W) map's axis: 0 rows (top-bottom), 1 columns.
SWAP_TABLES = {0: SWAP_UP_DOWN, 1: SWAP_LEFT_RIGHT}
# The three mirror images of a map, as the map axes each flips, in with_mirrors' order:
# left-right, top-bottom, both.
MIRROR_IMAGES = ((1,), (0,), (1, 0))


def swap_words(text: str, table: dict[str, str]) -> str:
    """Return the instruction's tokens with each direction word replaced by its mirror image."""
    words = tokenize(text)
    out = []
    for i, word in enumerate(words):
        keep = NOT_DIRECTIONS.get(word)
        if keep and (
            (i > 0 and words[i - 1] in keep['after'])
            or ' '.join(words[i + 1:i + 2]) in keep['before']
            or ' '.join(words[i + 1:i + 3]) in keep['before']
        ):
            out.append(word)
        else:
            out.append(table.get(word, word))
    return ' '.join(out)


def mirror_instruction(text: str, axes: tuple[int, ...]) -> str:
    """Return the instruction of a map flipped over `axes` (map axes, see SWAP_TABLES)."""
    for axis in axes:
        text = swap_words(text, SWAP_TABLES[axis])
    return text


def mirror_cell(
    cell: tuple[int, int], shape: tuple[int, int], axes: tuple[int, ...]
) -> tuple[int, int]:
    """Where `cell` of an (H, W) map lands when the map is flipped over `axes`."""
    return tuple(n - 1 - c if a in axes else c for a, (c, n) in enumerate(zip(cell, shape)))


def mirror(data: GroundingSet, axis: int) -> GroundingSet:
    """Mirror the (N, H, W) arrays; axis 2: left-right (columns), axis 1: top-bottom (rows)."""
    if axis not in (1, 2):
        raise ValueError(f'mirror axis must be 1 (rows) or 2 (columns), not {axis}')
    table = SWAP_TABLES[axis - 1]

    def flip(a: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(np.flip(a, axis=axis))

    goals = data.goals.copy()
    size = data.grids.shape[axis]
    goals[:, axis - 1] = size - 1 - goals[:, axis - 1]
    return GroundingSet(
        f'{data.name} mirrored',
        data.entities,
        flip(data.grids),
        [swap_words(t, table) for t in data.instructions],
        flip(data.values),
        flip(data.rewards),
        flip(data.terminal),
        goals,
        list(data.worlds),
    )


def with_mirrors(data: GroundingSet) -> GroundingSet:
    """Return the data set plus its MIRROR_IMAGES: left-right, top-bottom and both ways (4x)."""
    images = []
    for axes in MIRROR_IMAGES:
        image = data
        for axis in axes:
            image = mirror(image, axis + 1)  # map axis -> axis of the (N, H, W) arrays
        images.append(image)
    return GroundingSet.concat(data.name, [data, *images])


def add_distractors(
    model, grids: torch.Tensor, goals: torch.Tensor, most: int, rng: np.random.Generator
) -> torch.Tensor:
    """
    Put 0..`most` distractor objects on free cells of each map; return the new grids.

    A distractor is of one of the model's distractor kinds (ModelConfig.distractor_kinds),
    whose embedding rows are redrawn from N(0, 1) here, at every step, so no draw is ever
    learned: the model learns to pass over objects it does not know. They stand on free cells
    other than the goal (noise.free_cells, where the robustness study's unseen objects go too,
    which are other rows, held out), so the value maps stay true. `rng` alone draws
    everything: processes of one data-parallel run, given the same whole batch and generator,
    agree. The model must have distractor rows (its Capabilities' distractor_rows).
    """
    if not model.capabilities.distractor_rows:
        raise ValueError(f'{type(model).__name__} has no distractor kinds')
    ids = np.array(model.distractor_kinds())
    if most > len(ids):
        raise ValueError(
            f'{most} distractors need as many distractor kinds; the model has {len(ids)}'
        )
    model.redraw_distractors(rng.standard_normal)
    grids = grids.clone()
    for grid, goal, k in zip(grids.numpy(), goals.numpy(), rng.integers(0, most + 1, len(grids))):
        cells = free_cells(grid, goal)
        k = min(k, len(cells))
        grid.reshape(-1)[rng.permutation(cells)[:k]] = rng.permutation(ids)[:k]
    return grids


def filler_word_ids(vocab: Vocabulary) -> np.ndarray:
    """Return the ids of the filler words training inserts: noise.VERBS and noise.ARTICLES."""
    return np.array([vocab.index[w] for w in (*VERBS, *ARTICLES) if w in vocab.index])


def absent_name_pools(
    grids: torch.Tensor, tokens: torch.Tensor, name_ids: np.ndarray
) -> list[np.ndarray]:
    """
    Return, per example, the word ids of the kinds neither on its map nor named in it.

    `name_ids[kind]` is the kind's name's word id (-1: none in the vocabulary). These are the
    names the robustness study's text-noise inserts, as the paper's noise does.
    """
    kinds = np.flatnonzero(name_ids >= 0)
    out = []
    for grid, row in zip(grids.numpy(), tokens.numpy()):
        on_map = np.isin(kinds, grid)
        named = np.isin(name_ids[kinds], row)
        out.append(name_ids[kinds[~on_map & ~named]])
    return out


def insert_noise_words(
    tokens: torch.Tensor,
    fillers: np.ndarray,
    most: int,
    rng: np.random.Generator,
    absent_names: list[np.ndarray] | None = None,
    unknown: bool = True,
    share: float = NOISE_SHARE,
) -> torch.Tensor:
    """
    Insert noise words into a `share` of a batch's instructions; return the new (B, L') tokens.

    The textual counterpart of add_distractors: an instruction chosen gets 1..`most` words at
    one random position, as the robustness study inserts them, each an unknown word (<unk>,
    what any word outside the vocabulary becomes) or, with equal chance, a filler word
    (`fillers`: filler_word_ids). Names of kinds are inserted only with `absent_names` (per
    instruction, absent_name_pools: kinds neither on its map nor named in it; then a third of
    the words each): a name is content, and the Grounder leaves out the names of landmarks the
    map does not hold, but the network alone reads them. Without `unknown` (for a model that
    reads past unknown words, to which one is no noise) no <unk> is drawn: the words are
    fillers, or fillers and names half each (a name from an empty pool is still <unk>). The
    rest stay clean, so clean instructions keep their weight. `rng` alone draws
    everything, so data-parallel processes agree.
    """
    lengths = (tokens != PAD).sum(1).tolist()
    out = torch.full((len(tokens), tokens.shape[1] + most), PAD, dtype=tokens.dtype)
    for i, (row, n) in enumerate(zip(tokens.tolist(), lengths)):
        k = int(rng.integers(1, most + 1)) if rng.random() < share else 0
        at = int(rng.integers(0, n + 1))
        if absent_names is None:
            words = [
                UNK if (unknown and draw) or not len(fillers)
                else int(fillers[rng.integers(len(fillers))])
                for draw in rng.random(k) < 0.5
            ]
        else:  # a third each: an unknown word, a filler, the name of a kind the map lacks
            pools = (None, fillers, absent_names[i])[0 if unknown else 1:]
            words = []
            for choice in np.minimum((rng.random(k) * len(pools)).astype(int), len(pools) - 1):
                pool = pools[choice]
                empty = pool is None or not len(pool)
                words.append(UNK if empty else int(pool[rng.integers(len(pool))]))
        out[i, :n + k] = torch.tensor(row[:at] + words + row[at:n], dtype=tokens.dtype)
    return out
