# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Distances in metres, and counts past what the network learned.

"Two metres south of the sink" on a map of 0.25 m cells is eight cells below it. A
distance in metres (m, metres, meters, cm; digits, decimals or a number word) becomes a count
of cells at the map's cell size, rounded, at least one. The network learned counts up to four
cells; a longer count along a direction grounds as "four" that way and the rest is added to
the goal afterwards (`Offsets.extra`), so "seven below the rock" lands three cells past the
network's "four below the rock".
"""

from __future__ import annotations

from dataclasses import dataclass
import functools
import re

from text_to_num import alpha2digit

from .checks import DIRECTIONS, NUMBERS
from .vocabulary import LENGTH_UNITS

LEARNED_COUNT = 4  # the longest count the network was trained on
# number words (one .. twelve), as the structural checks read them
_NUMBER_WORDS = {w: n for w, n in NUMBERS.items() if w.isalpha()}
COUNT_WORDS = {n: w for w, n in _NUMBER_WORDS.items() if n <= LEARNED_COUNT}
# an amount of a length: digits, a number word, "a", "half a", and "and a half" after it
_AMOUNT = (
    r'(?P<n>\d+(?:[.,]\d+)?|half an?|an?|' + '|'.join(_NUMBER_WORDS) + r')'
    r'(?P<half1>\s+and\s+a\s+half)?'
)
# a unit of length after an amount (wording.count_first reads it too): vocabulary.LENGTH_UNITS
METRIC_UNIT = '|'.join(sorted(map(re.escape, LENGTH_UNITS), key=len, reverse=True))
_METRIC = re.compile(
    rf'\b{_AMOUNT}\s*(?P<unit>{METRIC_UNIT})\b(?P<half2>\s+and\s+a\s+half)?', re.IGNORECASE
)
# cardinal number words past three ("six", "twenty one"), read by text2num into digits; one to
# three stay words, as the network learned them
_CARDINAL = re.compile(
    r'\b(?:(?:zero|one|two|three|four|five|six|seven|eight|nine|ten|eleven|twelve|thirteen|'
    r'fourteen|fifteen|sixteen|seventeen|eighteen|nineteen|twenty|thirty|forty|fifty|sixty|'
    r'seventy|eighty|ninety|hundred|point)(?:[\s-]+|\b))+',
    re.IGNORECASE,
)
_UNIT_WORD = r'(?:\s+(?:cells?|squares?|steps?|spaces?|tiles?|spots?))?'
# a count followed, after an optional unit, by the direction it goes
_COUNT = re.compile(
    rf'\b(?P<n>\d+|{"|".join(_NUMBER_WORDS)}){_UNIT_WORD}(?P<rest>\s+(?:to\s+the\s+)?'
    rf'(?P<dir>{"|".join(DIRECTIONS)})\b)',
    re.IGNORECASE,
)


@dataclass(frozen=True)
class Offsets:
    """An instruction's distances in cells: in full, as the network reads it, and the rest."""

    text: str  # every distance in cells, in full ("8 below the sink"): what the checks read
    model_text: str  # counts past LEARNED_COUNT cut to it: what the network reads
    extra: tuple[int, int]  # (rows, cols) to add to the network's goal


def _amount(text: str) -> float:
    text = text.lower()
    if text.startswith('half'):
        return 0.5
    if text in ('a', 'an'):
        return 1.0
    return float(_NUMBER_WORDS.get(text) or text.replace(',', '.'))  # 1,5 m is 1.5 m


# "a couple of metres" is two; "a bit left of", "slightly above" a step, as "left of" is
_COUPLE = re.compile(r'\ba (?:couple|pair)(?: of)?\b', re.IGNORECASE)
_A_BIT = re.compile(
    r'\b(?:(?:just )?a (?:little )?(?:bit|tad)|a little|slightly|somewhat)\b ?', re.IGNORECASE
)


def digits(text: str) -> str:
    """
    Return the text with each cardinal number past three in digits: "6 feet" for "six feet".

    "A couple of" is two; "a bit", "a little" and "slightly" say no more than the side after
    them ("a bit left of the sofa": left of it, one cell).
    """
    text = _A_BIT.sub('', _COUPLE.sub('two', text))

    def number(match: re.Match) -> str:
        said = match.group(0)
        out = alpha2digit(said.strip(), 'en')
        return out + said[len(said.rstrip()):]

    return _CARDINAL.sub(number, text)


def in_cells(instruction: str, cell_size: float | None) -> str:
    """
    Return the instruction with each distance in metres as a count of cells.

    Raises ValueError for a distance in metres when the cell size is not known.
    """

    def cells(match: re.Match) -> str:
        if cell_size is None:
            raise ValueError(
                f'{match.group(0)!r} is a distance in metres; grounding it needs the map cell '
                'size in metres (cell_size; the ground command: --cell-size)'
            )
        half = 0.5 if match.group('half1') or match.group('half2') else 0.0
        metres = (_amount(match.group('n')) + half) * LENGTH_UNITS[match.group('unit').lower()]
        return str(max(1, round(metres / cell_size)))

    if cell_size is not None and not cell_size > 0:
        raise ValueError(f'cell_size must be a positive number of metres, got {cell_size}')
    return _METRIC.sub(cells, instruction)


@functools.lru_cache(maxsize=256)  # a node grounds the same instruction on every new map
def offsets(instruction: str, cell_size: float | None = None) -> Offsets:
    """
    Return an instruction's distances in cells (in_cells), split at LEARNED_COUNT.

    Both texts word a count as one word and drop its unit ("2 cells below": "two below"), so
    their words line up.
    """
    text = in_cells(instruction, cell_size)
    extra = [0, 0]

    def count(match: re.Match) -> int:
        n = match.group('n').lower()
        return _NUMBER_WORDS.get(n) or int(n)

    def full(match: re.Match) -> str:
        n = count(match)
        return COUNT_WORDS.get(n, str(n)) + match.group('rest')

    def cut(match: re.Match) -> str:
        n = count(match)
        step = DIRECTIONS[match.group('dir').lower()]
        if n > LEARNED_COUNT:
            extra[0] += (n - LEARNED_COUNT) * step[0]
            extra[1] += (n - LEARNED_COUNT) * step[1]
            n = LEARNED_COUNT
        return COUNT_WORDS.get(n, str(n)) + match.group('rest')

    model_text = _COUNT.sub(cut, text)
    return Offsets(_COUNT.sub(full, text), model_text, (extra[0], extra[1]))
