# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The robustness study's noise (paper section 5.3), as seeded transforms of a data set.

- obs-noise: k objects of k different unseen kinds on free cells of each map. Unseen
  kinds are embedding rows no training map ever held (models.EntityEncoder); a free cell
  holds the table's kind 0 (grass, the empty board) and is not the goal, so a referenced
  object, or any object, is never covered. They are neither obstacles nor goals, so the true
  value maps stay those of the clean map.
- text-noise: k words inserted at one random position of each instruction: verbs (go,
  reach, locate), articles, and names of kinds that are neither on the map nor referenced,
  as in the paper. Words the checkpoint's vocabulary lacks are left out of the pool: they
  would be unknown words, the third noise.
- unknown-words: k words outside the checkpoint's vocabulary inserted at one random position
  (a user who paraphrases); the model sees each as <unk>.

Each map draws from a generator of its own, seeded by (seed, noise, map index), and k
takes the first k of a fixed sequence of draws: the noise at k = 5 is that at k = 2 plus
three more, on every map, so a curve over k measures more noise on the same maps.
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

from .datasets import GroundingSet
from ..core.entities import EntityTable
from ..core.text import tokenize, Vocabulary
from ..models.config import ModelConfig
from ..models.encoders import unseen_kind_ids
from ..models.protocol import Capabilities

NOISES = ('obs-noise', 'text-noise', 'unknown-words')
MAX_K = ModelConfig.unseen_kinds  # the paper's 1..10; also the unseen kinds a model holds
FREE_KIND = 0  # grass (PuddleWorld), the empty board (ISI)
VERBS = ('go', 'reach', 'locate')
ARTICLES = ('the', 'a', 'an')
# Words a paraphrasing user might add; those in a checkpoint's vocabulary are left out.
PARAPHRASE_WORDS = (
    'please', 'kindly', 'proceed', 'navigate', 'head', 'wander', 'stroll', 'hurry', 'destination',
    'location', 'position', 'tile', 'square', 'area', 'spot', 'somewhere', 'nearby', 'robot',
    'quickly', 'carefully', 'okay', 'um', 'thereabouts', 'vicinity', 'ultimately', 'eventually',
)
# Name prefixes that say what sort of thing a kind is, not which one (ISI's logo_, digit_).
CATEGORY_PREFIXES = ('logo_', 'digit_')


def kind_words(entities: EntityTable, kind: int) -> list[str]:
    """Return the words an instruction uses for a kind: 'logo_burger_king' -> burger, king."""
    name = entities.names[kind]
    for prefix in CATEGORY_PREFIXES:
        name = name.removeprefix(prefix)
    return name.split('_')


def word_forms(word: str) -> tuple[str, str, str]:
    """Return a name word as itself and with a plural s/es ('rock', 'rocks', 'rockes')."""
    return word, word + 's', word + 'es'


def kind_word_ids(entities: EntityTable, vocab: Vocabulary) -> tuple[tuple[int, ...], ...]:
    """Return each kind's words in all their forms (word_forms), as `vocab`'s ids."""
    return tuple(
        tuple(
            vocab.index[form]
            for word in kind_words(entities, kind)
            for form in word_forms(word)
            if form in vocab.index
        )
        for kind in range(len(entities))
    )


def referenced_kinds(instruction: str, entities: EntityTable) -> set[int]:
    """
    Return the kinds an instruction references.

    The rule: a kind is referenced when its words (kind_words) occur in a row among the
    instruction's words, each word as itself or with a plural s/es ('rocks' references rock).
    It errs on the side of too many (ISI's 'move 3 spaces' references block 3), which only
    makes the noise avoid more.
    """
    tokens = tokenize(instruction)
    found = set()
    for kind in range(len(entities)):
        words = kind_words(entities, kind)
        for start in range(len(tokens) - len(words) + 1):
            if all(t in word_forms(w) for t, w in zip(tokens[start:], words)):
                found.add(kind)
                break
    return found


def _check_k(noise: str, k: int) -> None:
    if noise not in NOISES:
        raise ValueError(f'unknown noise {noise!r}; use one of {", ".join(NOISES)}')
    if not 0 <= k <= MAX_K:
        raise ValueError(f'{noise}: k must be in 0..{MAX_K}, got {k}')


def _map_rng(seed: int, noise: str, index: int) -> np.random.Generator:
    return np.random.default_rng([seed, NOISES.index(noise), index])


def free_cells(grid: np.ndarray, goal) -> np.ndarray:
    """Return the flat indices of a map's free cells other than the goal: where objects may go."""
    free = grid == FREE_KIND
    free[tuple(goal)] = False
    return np.flatnonzero(free)


def add_unseen_objects(data: GroundingSet, k: int, seed: int) -> GroundingSet:
    """Put k objects of k different unseen kinds on free cells of each map (not the goal)."""
    _check_k('obs-noise', k)
    if k == 0:
        return data
    unseen = np.array(unseen_kind_ids(len(data.entities), MAX_K))
    grids = data.grids.copy()
    for i, (grid, goal) in enumerate(zip(grids, data.goals)):
        cells = free_cells(grid, goal)
        if len(cells) < k:
            raise ValueError(
                f'{data.name}: map {i} has {len(cells)} free cells, too few for {k} unseen objects'
            )
        rng = _map_rng(seed, 'obs-noise', i)
        grid.reshape(-1)[rng.permutation(cells)[:k]] = rng.permutation(unseen)[:k]
    return replace(data, grids=grids, name=f'{data.name}+obs-noise{k}')


def _insert_words(
    data: GroundingSet, noise: str, k: int, seed: int, pools: list[list[str]]
) -> GroundingSet:
    """Insert k words drawn from `pools[i]` at one random position of instruction i."""
    instructions = []
    for i, (text, pool) in enumerate(zip(data.instructions, pools)):
        if not pool:
            raise ValueError(f'{data.name}: no {noise} words left for instruction {i} ({text!r})')
        rng = _map_rng(seed, noise, i)
        words = tokenize(text)
        at = int(rng.integers(0, len(words) + 1))
        inserted = [pool[j] for j in rng.integers(0, len(pool), size=MAX_K)[:k]]
        instructions.append(' '.join(words[:at] + inserted + words[at:]))
    return replace(data, instructions=instructions, name=f'{data.name}+{noise}{k}')


def noise_words(grid: np.ndarray, text: str, entities: EntityTable, vocab: Vocabulary) -> list:
    """
    Return the words text-noise draws from for one example, those in `vocab` only.

    Verbs, articles, and the names of kinds that are neither on the map nor referenced.
    """
    absent = set(range(len(entities))) - set(np.unique(grid).tolist())
    absent -= referenced_kinds(text, entities)
    names = [w for kind in sorted(absent) for w in kind_words(entities, kind)]
    words = [*VERBS, *ARTICLES, *names]
    return [w for w in words if w in vocab.index]


def add_noise_words(data: GroundingSet, vocab: Vocabulary, k: int, seed: int) -> GroundingSet:
    """Insert k verbs, articles and names of absent, unreferenced kinds into each instruction."""
    _check_k('text-noise', k)
    if k == 0:
        return data
    pools = [
        noise_words(grid, text, data.entities, vocab)
        for grid, text in zip(data.grids, data.instructions)
    ]
    return _insert_words(data, 'text-noise', k, seed, pools)


def add_unknown_words(data: GroundingSet, vocab: Vocabulary, k: int, seed: int) -> GroundingSet:
    """Insert k words the vocabulary lacks into each instruction."""
    _check_k('unknown-words', k)
    if k == 0:
        return data
    pool = [w for w in PARAPHRASE_WORDS if w not in vocab.index]
    return _insert_words(data, 'unknown-words', k, seed, [pool] * len(data))


def add_noise(
    data: GroundingSet, vocab: Vocabulary, noise: str, k: int, seed: int = 0
) -> GroundingSet:
    """Return `data` with k of one noise (NOISES) added; k = 0 returns it unchanged."""
    _check_k(noise, k)
    if noise == 'obs-noise':
        return add_unseen_objects(data, k, seed)
    if noise == 'text-noise':
        return add_noise_words(data, vocab, k, seed)
    return add_unknown_words(data, vocab, k, seed)


def require_unseen_rows(model, name: str) -> None:
    """
    Fail clearly when a model has no embedding rows for the MAX_K unseen kinds.

    The model's Capabilities say whether its entity table has unseen rows at all (t-UVFA's has
    none); one that has them must hold as many as obs-noise may place.
    """
    capabilities = getattr(model, 'capabilities', Capabilities())
    if not capabilities.unseen_rows or len(model.unseen_kinds()) < MAX_K:
        raise ValueError(
            f'{name} has no embedding rows for unseen kinds, so it cannot be given unseen '
            f'objects (a model needs {MAX_K} of them)'
        )


# --- command-line options (eval, robustness) ---------------------------------------------


def noise_count(text: str) -> int:
    """Parse a noise amount k: an integer in 0..MAX_K."""
    try:
        k = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text!r} is not a whole number') from None
    if not 0 <= k <= MAX_K:
        raise argparse.ArgumentTypeError(f'{k} is outside 0..{MAX_K}')
    return k


def add_noise_options(p) -> None:
    """--obs-noise, --text-noise, --unknown-words and --seed (noise.py)."""
    p.add_argument(
        '--obs-noise', type=noise_count, default=0, metavar='K',
        help='put K objects of K unseen kinds on free cells of every map',
    )
    p.add_argument(
        '--text-noise', type=noise_count, default=0, metavar='K',
        help='insert K verbs, articles and absent object names at one position',
    )
    p.add_argument(
        '--unknown-words', type=noise_count, default=0, metavar='K',
        help='insert K out-of-vocabulary words at one position',
    )
    p.add_argument('--seed', type=int, default=0, help='seed of the noise')
