# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Finding an entity table's landmarks in an instruction: names, aliases, plurals, typos.

A user's table names its own landmarks ("fridge", "coffee machine") and may give other words
for each (`aliases`). `Lexicon.mentions` finds them in an instruction, longest phrase first:
case and punctuation do not matter, a plural ("fridges", "boxes", "libraries") is its
singular, and a word one edit (a letter changed, added, dropped or two swapped) from a name
of four letters or more is that name, unless the word is one the lexicon is told to leave
alone (`protected`: the relation words a model reads, so "three" never becomes "tree").
"""

from __future__ import annotations

from dataclasses import dataclass
import functools
from importlib.resources import files
from typing import Iterable

import numpy as np
from rapidfuzz.distance import OSA

from ..core.entities import EntityTable
from ..core.footprints import count_footprints
from ..core.text import tokenize

# only a name this long is read through a typo: shorter ones are one edit from too many words
TYPO_MIN_LETTERS = 4


@dataclass(frozen=True)
class Mention:
    """One landmark named in an instruction: its kind and the words [start, end) that name it."""

    kind: int
    start: int
    end: int
    words: tuple[str, ...]


def singular(word: str) -> str:
    """Return the singular of an English plural noun by the regular rules, else the word."""
    if len(word) > 4 and word.endswith('ies'):
        return word[:-3] + 'y'
    if len(word) > 4 and word.endswith(('ches', 'shes', 'sses', 'xes', 'zes')):
        return word[:-2]
    if len(word) > 3 and word.endswith('s') and not word.endswith(('ss', 'us', 'is')):
        return word[:-1]
    return word


def within_one_edit(a: str, b: str) -> bool:
    """Return whether a and b differ by at most one substitution, insertion, deletion or swap."""
    return OSA.distance(a, b, score_cutoff=1) <= 1


# a word this frequent in English text is a word of its own, never read as a typo of a name
# ("hall" is no "wall", "street" no "tree"); rarer ones may be ("hose" for "horse")
ENGLISH_MIN_COUNT = 20_000_000


@functools.cache
def english_words() -> frozenset[str]:
    """Return the common English words of symspellpy's frequency dictionary."""
    text = (files('symspellpy') / 'frequency_dictionary_en_82_765.txt').read_text()
    words = (line.split() for line in text.splitlines())
    return frozenset(w for w, n in words if int(n) >= ENGLISH_MIN_COUNT)


def short_typo(word: str, name: str) -> bool:
    """
    Return whether `word` is a typo of a three-letter name: one letter changed, not the first.

    Shorter names are one edit from too many words for any other edit to be read as one.
    """
    return (
        len(name) == 3
        and len(word) == 3
        and word[0] == name[0]
        and word not in COMMON_WORDS
        and sum(a != b for a, b in zip(word, name)) == 1
    )


def phrase_words(name: str) -> tuple[str, ...]:
    """Return the words of a name as an instruction would say them ('coffee_machine')."""
    return tuple(tokenize(name.replace('_', ' ')))


class Lexicon:
    """The phrases that name each kind of an entity table, and a finder of them in text."""

    def __init__(self, table: EntityTable, protected: Iterable[str] = ()):
        self.table = table
        self.protected = frozenset(protected)
        phrases: dict[tuple[str, ...], int] = {}
        for kind, name in enumerate(table.names):
            if kind == table.free_kind:  # free ground is where a goal is, never a landmark:
                continue  # "the tile above the oven" with a floor of `tiles` is a cell
            for text in (name, *table.aliases_of(kind)):
                words = phrase_words(text)
                if not words:
                    continue
                # the singular form of the last word is the key; a clash names both kinds'
                # phrase twice, and the table's own order decides (the first kind keeps it)
                phrases.setdefault(words[:-1] + (singular(words[-1]),), kind)
        self.phrases = phrases
        self.longest = max((len(p) for p in phrases), default=0)
        self.typo_words = {p[0]: k for p, k in phrases.items() if len(p) == 1}
        # the reading asks for the landmarks of the same words many times (each clause, step
        # and check): each word list is read once
        self.found = functools.lru_cache(maxsize=1024)(self._found)

    def word_kind(self, word: str) -> int | None:
        """Return the kind a single word names (exact, plural or typo), or None."""
        exact = self.phrases.get((singular(word),))
        if exact is not None:
            return exact
        if len(word) < TYPO_MIN_LETTERS - 1 or word in self.protected:
            return None
        if word in english_words():
            return None
        close = {
            k
            for w, k in self.typo_words.items()
            if (len(w) >= TYPO_MIN_LETTERS and within_one_edit(word, w))
            or (len(w) >= TYPO_MIN_LETTERS and within_one_edit(singular(word), w))
            or short_typo(word, w)
        }
        return close.pop() if len(close) == 1 else None

    def phrase_kind(self, key: tuple[str, ...]) -> int | None:
        """Return the kind a phrase of several words names, with one typo at most, or None."""
        if key in self.phrases:
            return self.phrases[key]
        close = {
            kind
            for phrase, kind in self.phrases.items()
            if len(phrase) == len(key)
            and sum(a != b for a, b in zip(phrase, key)) == 1
            and all(
                a == b
                or (
                    len(a) >= TYPO_MIN_LETTERS
                    and b not in self.protected
                    and within_one_edit(a, b)
                )
                for a, b in zip(phrase, key)
            )
        }
        return close.pop() if len(close) == 1 else None

    def mentions(self, instruction: str | list[str]) -> list[Mention]:
        """Return the landmarks an instruction names, in order, longest phrase first."""
        words = tokenize(instruction) if isinstance(instruction, str) else instruction
        return list(self.found(tuple(words)))

    def _found(self, words: tuple[str, ...]) -> tuple[Mention, ...]:
        found, i = [], 0
        while i < len(words):
            for n in range(min(self.longest, len(words) - i), 1, -1):
                kind = self.phrase_kind(tuple(words[i:i + n - 1]) + (singular(words[i + n - 1]),))
                if kind is not None:
                    found.append(Mention(kind, i, i + n, tuple(words[i:i + n])))
                    i += n
                    break
            else:
                kind = self.word_kind(words[i])
                if kind is not None:
                    found.append(Mention(kind, i, i + 1, (words[i],)))
                i += 1
        return tuple(found)

    def mentioned_kinds(self, instruction: str | list[str]) -> list[int]:
        """Return the kinds an instruction names, each once, in order of first mention."""
        return list(dict.fromkeys(m.kind for m in self.mentions(instruction)))


# Words the lexicon never reads as a typo of a name: the relation words, numbers and common
# words of instructions ("three" is one edit from "tree", "start" from "star").
COMMON_WORDS = frozenset(
    """
    a an the this that these those it its is are be to of in on at by for from with and or
    not no any all each every one two three four five six seven eight nine ten first second
    third last next near nearest close closer closest far farther farthest further furthest
    between beside behind front middle center centre corner edge side row column line cell
    cells square squares space spaces step steps block blocks spot tile place area point
    above below under beneath underneath over up down top bottom left right north south east
    west upper lower high low there here where then than them they what when which who
    start stop stay stand go move drive walk reach find get head navigate come turn park
    please robot should would could will can must just only then now same other another
    direct directly exactly immediately right
    """.split()
)
# how a Translation gives the model's own names their kinds: by name but for a reference by
# distance (the default), by name always, or by role always (the ablation's other two)
KINDS_BY = ('name', 'name-always', 'role')
# words of a reference that picks a landmark by its distance to another
DISTANCE_WORDS = frozenset('closest nearest closer nearer'.split())
# how a reference names its target and its landmarks, for choosing the kinds they become
EXTREME_WORDS = frozenset(
    """
    northernmost southernmost easternmost westernmost northmost southmost eastmost westmost
    topmost bottommost leftmost rightmost uppermost lowermost highest lowest northeasternmost
    northwesternmost southeasternmost southwesternmost
    """.split()
)
RELATION_WORDS = frozenset(
    """
    closest nearest farthest furthest between one two three four five six seven eight nine
    ten above below under beneath underneath over left right north south east west northeast
    northwest southeast southwest near next beside
    """.split()
) | frozenset(str(n) for n in range(10))
FILLER_WORDS = frozenset('the a an that which is'.split())


def count_objects(grid: np.ndarray, kind: int) -> int:
    """
    Return how many landmarks of a kind a map holds: its 8-connected groups of cells.

    A landmark drawn over several cells (a robot map's footprint) is one landmark.
    """
    return count_footprints(grid, kind)


@dataclass(frozen=True)
class Translated:
    """A user's map and instruction in a model's own kinds and words."""

    grid: np.ndarray
    instruction: str
    mentions: tuple[Mention, ...]
    kinds: dict[int, int]  # each mentioned user kind -> the model kind it became


class Translation:
    """
    Ground any entity table with a model that knows PuddleWorld's landmarks.

    The landmarks an instruction names become the model's landmark kinds, in order of
    mention; every other landmark becomes free ground, and the table's obstacles the
    model's obstacle. A named kind the model knows by its name keeps it. Another named kind
    that the map holds more than once (touching cells are one landmark), that an extreme
    picks ("the westernmost chair") or that a relation follows ("the chair closest to the
    sofa") becomes one of the model's non-unique kinds (rock, tree, house, horse), the
    others one of its unique kinds (star ... diamond): the roles those kinds played in its
    training. A reference by distance ("the tree closest to the heart") takes roles for
    the model's own names too (DISTANCE_WORDS; `kinds_by` 'name-always' or 'role' for the
    ablation). The instruction's words are kept; only the
    names are replaced, and the names of landmarks the map does not hold are left out.
    """

    def __init__(
        self, table: EntityTable, model: EntityTable, unique, nonunique, kinds_by: str = 'name'
    ):
        if kinds_by not in KINDS_BY:
            raise ValueError(f'kinds_by must be one of {", ".join(KINDS_BY)}, got {kinds_by!r}')
        self.kinds_by = kinds_by
        self.lexicon = Lexicon(table, COMMON_WORDS)
        self.table, self.model = table, model
        self.unique = [model.index(n) for n in unique]
        self.nonunique = [model.index(n) for n in nonunique]
        self.free = model.free_kind
        self.obstacle = model.obstacles[0]
        landmarks = set(self.unique) | set(self.nonunique)
        self.same_kind = {
            k: model.index(n)
            for k, n in enumerate(table.names)
            if n in model.names and model.index(n) in landmarks
        }

    def _many(self, mention: Mention, words: list[str], count: int) -> bool:
        """Return whether a mentioned kind takes a non-unique kind of the model."""
        before = [w for w in words[:mention.start] if w not in FILLER_WORDS][-1:]
        after = [w for w in words[mention.end:] if w not in FILLER_WORDS][:1]
        return count > 1 or bool(set(before) & EXTREME_WORDS) or bool(set(after) & RELATION_WORDS)

    def __call__(self, grid: np.ndarray, instruction: str) -> Translated:
        words = tokenize(instruction)
        return self.translate(grid, words, self.lexicon.mentions(words))

    def translate(self, grid: np.ndarray, words: list[str], mentions: list[Mention]) -> Translated:
        """Return the map and the words in the model's kinds, the landmarks `mentions` named."""
        words = list(words)
        unique, nonunique = list(self.unique), list(self.nonunique)
        kinds: dict[int, int] = {}
        # a distance reference grounds its landmarks by role even where the model knows
        # their names: its far relation scores some kinds' rows worse than the roles' kinds
        # on large maps ("closest to the heart" at 32x32: 3 of 18, against 94% for the rest)
        by_name = self.kinds_by == 'name-always' or (
            self.kinds_by == 'name' and not set(words) & DISTANCE_WORDS
        )
        for m in mentions:
            # a landmark the map does not hold cannot be the referent: its name is left out
            # of what the model reads (the grounding declines with referent-missing)
            if m.kind in kinds or m.kind in self.table.obstacles or not (grid == m.kind).any():
                continue
            same = self.same_kind.get(m.kind) if by_name else None
            if same is not None:  # a kind the model knows by name keeps it
                kinds[m.kind] = same
                for pool in (unique, nonunique):
                    if same in pool:
                        pool.remove(same)
                continue
            pool = nonunique if self._many(m, words, count_objects(grid, m.kind)) else unique
            pool = pool or unique or nonunique  # more named kinds than the model has of a role
            if pool:
                kinds[m.kind] = pool.pop(0)
        out = np.full(grid.shape, self.free, dtype=np.int64)
        for k in self.table.obstacles:
            out[grid == k] = self.obstacle
        for k, model_kind in kinds.items():
            out[grid == k] = model_kind
        said, start = [], 0
        for m in mentions:
            said += words[start:m.start]
            if m.kind in kinds:
                said.append(self.model.names[kinds[m.kind]])
            elif m.kind in self.table.obstacles:
                said.append(self.model.names[self.obstacle])
            start = m.end
        said += words[start:]
        return Translated(out, ' '.join(said), tuple(mentions), kinds)
