# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Generated worlds in another entity table: the same layout and answer, other landmarks.

A PuddleWorld-style world of the generator becomes one of a user's table: grass its first
free kind, puddles its first obstacle (or free ground if it has none), and each landmark
kind a distinct landmark kind of the table (drawn at random; the kinds the instruction names
first, so they always get one; a landmark kind left over when the table has none to spare
becomes free ground). The instruction names the new kinds by their name, by one of their
aliases, or with a one-letter typo (`NAMINGS`).
"""

from __future__ import annotations

import numpy as np

from .generator import GRASS, PUDDLE
from ..core.entities import EntityTable, PUDDLEWORLD
from ..core.text import tokenize
from ..language.lexicon import phrase_words

NAMINGS = ('name', 'alias', 'typo')
LETTERS = 'abcdefghijklmnopqrstuvwxyz'


def landmark_kinds(table: EntityTable) -> list[int]:
    """Return the kinds of a table that can stand for a landmark: not its ground, no obstacle."""
    free = [k for k in range(len(table)) if k not in table.obstacles]
    if len(free) < 2:
        raise ValueError(f'the {table.domain} table needs a free kind and at least one landmark')
    return free[1:]


def typo(word: str, rng: np.random.Generator) -> str:
    """Return the word with one letter changed, dropped or added, or two swapped (not the 1st)."""
    i = int(rng.integers(1, len(word)))
    edit = int(rng.integers(4))
    if edit == 0:  # changed
        other = [c for c in LETTERS if c != word[i]]
        return word[:i] + other[rng.integers(len(other))] + word[i + 1:]
    if edit == 1:  # dropped
        return word[:i] + word[i + 1:]
    if edit == 2 or i == 1 or word[i - 1] == word[i]:  # added
        return word[:i] + LETTERS[rng.integers(26)] + word[i:]
    return word[: i - 1] + word[i] + word[i - 1] + word[i + 1:]  # swapped


def say(table: EntityTable, kind: int, naming: str, rng: np.random.Generator) -> str:
    """Return how an instruction names a kind: its name, an alias or a typo of its name."""
    if naming not in NAMINGS:
        raise ValueError(f'unknown naming {naming!r}; use one of {", ".join(NAMINGS)}')
    aliases = table.aliases_of(kind)
    if naming == 'alias' and aliases:
        return ' '.join(phrase_words(aliases[rng.integers(len(aliases))]))
    words = list(phrase_words(table.names[kind]))
    if naming == 'typo':
        longest = max(range(len(words)), key=lambda i: len(words[i]))
        if len(words[longest]) >= 4:  # the lexicon reads typos of names this long
            words[longest] = typo(words[longest], rng)
    return ' '.join(words)


def rename(
    grid: np.ndarray,
    instruction: str,
    table: EntityTable,
    rng: np.random.Generator,
    naming: str = 'name',
) -> tuple[np.ndarray, str]:
    """Return a generated PuddleWorld world and instruction in `table`'s kinds and names."""
    landmarks = [int(k) for k in rng.permutation(landmark_kinds(table))]
    free = table.free_kind
    words = tokenize(instruction)
    named = [PUDDLEWORLD.index(w) for w in words if w in PUDDLEWORLD.names]
    present = [int(k) for k in np.unique(grid) if k not in (GRASS, PUDDLE)]
    order = list(dict.fromkeys(named + present))
    if len(dict.fromkeys(named)) > len(landmarks):
        raise ValueError(
            f'the {table.domain} table has too few landmark kinds for {instruction!r}'
        )
    # puddles become the table's first obstacle, or free ground in a table without any
    mapping = {GRASS: free, PUDDLE: table.obstacles[0] if table.obstacles else free}
    mapping.update({k: landmarks[i] if i < len(landmarks) else free for i, k in enumerate(order)})
    out = np.vectorize(mapping.get, otypes=[np.int64])(grid)
    said = [
        say(table, mapping[PUDDLEWORLD.index(w)], naming, rng) if w in PUDDLEWORLD.names else w
        for w in words
    ]
    return out, ' '.join(said)
