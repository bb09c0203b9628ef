# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Finding phrases, sentences and misspelt words in an instruction's words (reading.py's tools).

Phrases are strings of lower-case words as `core.text.tokenize` gives them; `spelling` reads
a word one edit (two for long words) from a word that moves a goal as that word (rapidfuzz).
"""

from __future__ import annotations

import functools
import re

from rapidfuzz import process
from rapidfuzz.distance import OSA

from .checks import ARTICLES, CLAUSES, DIRECTIONS, EXTREME_SIDES, NUMBERS, PHRASE_ENDS
from .lexicon import RELATION_WORDS
from .places import UNIT_WORDS
from .vocabulary import GO_VERBS, LENGTH_UNITS

# the words a misspelt word may be read as (one edit; two for words of seven letters or more):
# the words that move the goal. Verbs and fillers are not among them: a misspelt verb moves
# nothing, and "hea" is likelier a name cut short than "head"
SPELLING_TARGETS = tuple(
    sorted(
        set(DIRECTIONS) | set(EXTREME_SIDES) | {w for w in NUMBERS if w.isalpha()}
        | set(UNIT_WORDS) | set(LENGTH_UNITS) | RELATION_WORDS
        | set('closest nearest farthest furthest between next beside cell square'.split())
    )
)

# where a landmark's name goes (after an article, ending its phrase: "go to the oven"), only
# a side or a cell can end the place said ("the lfet of the sofa": the left), so a misspelt
# word there is read only as one of those; no relation word or count ends a phrase ("the
# oven" is no "the over", "the even" no "the seven"): it stays a name the map may lack
NAME_SLOT_TARGETS = tuple(
    sorted(
        set('left right top bottom north south east west northeast northwest southeast '
            'southwest'.split()) | set(UNIT_WORDS)
    )
)


def phrase_at(words: list[str], i: int, phrases) -> str | None:
    """Return the longest of `phrases` (strings of words) that starts at words[i], or None."""
    if i >= len(words):
        return None
    for said, p in by_first_word(phrases).get(words[i], ()):
        if tuple(words[i:i + len(said)]) == said:
            return p
    return None


@functools.lru_cache(maxsize=64)
def by_first_word(phrases) -> dict[str, list[tuple[tuple[str, ...], str]]]:
    """
    Return `phrases` (a tuple or frozenset) by their first word, each as (words, phrase).

    Longest first, and of equal length in the phrases' order: a reading looks up a few dozen
    lists at every word, so each word sees only the phrases that can start there.
    """
    index: dict[str, list] = {}
    for p in phrases:
        said = tuple(p.split())
        if said:
            index.setdefault(said[0], []).append((said, p))
    for entries in index.values():
        entries.sort(key=lambda entry: -len(entry[0]))  # stable: ties keep their order
    return index


def find_phrase(words: list[str], phrases) -> list[tuple[int, str]]:
    """Return (index, phrase) for each place one of `phrases` starts, left to right."""
    found, i = [], 0
    while i < len(words):
        p = phrase_at(words, i, phrases)
        if p is not None:
            found.append((i, p))
            i += len(p.split())
        else:
            i += 1
    return found


_SENTENCE_END = re.compile(r'(?<![0-9])[.!;]+(?=\s|$)|\?+|(?<=[a-z])[.](?=\s*[A-Za-z])')


def sentences(text: str) -> list[str]:
    """Return the sentences of a text ("1.5 m" is no sentence end)."""
    return [s.strip() for s in _SENTENCE_END.split(text) if s and s.strip(' ,')]


# a count's words: what a misspelt word before a unit ("tow cells") is
COUNT_WORDS = tuple(sorted(w for w in NUMBERS if w.isalpha()))
PLURAL_UNITS = frozenset(u for u in UNIT_WORDS if u.endswith('s'))  # "two cells", not "a cell"


def spelling_targets(words: list[str], i: int) -> tuple[str, ...]:
    """Return the words that words[i], misspelt, may be read as, by where it stands."""
    after = words[i + 1] if i + 1 < len(words) else None
    # before units it is a count: "tow cells" (not "top"); before one unit ("um tile") it is
    # none, as one cell's count is a word known ("a", "one")
    if after in PLURAL_UNITS:
        return COUNT_WORDS
    if i and words[i - 1] in ARTICLES and (after is None or after in CLAUSES | PHRASE_ENDS):
        return NAME_SLOT_TARGETS
    return SPELLING_TARGETS


@functools.lru_cache(maxsize=4096)
def spelling(word: str, targets: tuple[str, ...] = SPELLING_TARGETS) -> str | None:
    """Return the relation word a misspelt word is one edit from (two if long), or None."""
    if len(word) < 3:
        return None
    limit = 1 if len(word) < 7 else 2
    found = process.extract(word, targets, scorer=OSA.distance, score_cutoff=limit, limit=2)
    if not found or (len(found) > 1 and found[1][1] == found[0][1]):
        return None
    return found[0][0]


def texted(words: list[str]) -> list[str]:
    """Return the words with a texter's "2" for "to" read as "to": "go 2 the fridge"."""
    return [
        'to' if w == '2' and words[i + 1:i + 2] in (['the'], ['a'], ['an'], ['my'])
        and (not i or words[i - 1] in GO_VERBS) else w
        for i, w in enumerate(words)
    ]
