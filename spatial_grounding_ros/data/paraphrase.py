# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The generator's instructions worded as people word them (our own grammar, language/wording.py).

`paraphrase` rewords a generated instruction: each phrase of language/wording.PHRASES may become
one of its other wordings, a count may gain a unit ("two squares below"), and a request may
open or close with filler ("please", "the robot should"). The landmark names are kept. The
suite measures the node on these (`suite --wording paraphrase`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .datasets import GroundingSet
from ..core.text import tokenize
from ..language.checks import NUMBERS
from ..language.wording import COUNTS, PHRASES

OPENINGS = ('', '', 'please', 'robot', 'the robot should', 'can you', 'now')
CLOSINGS = ('', '', 'please', 'thanks', 'now')
UNIT_WORDS = ('cells', 'squares', 'steps', 'spaces')
# canonical phrases, longest first, as word tuples
_CANONICAL = sorted(
    ((tuple(tokenize(c)), [tuple(tokenize(w)) for w in ws]) for c, ws in PHRASES.items() if c),
    key=lambda p: -len(p[0]),
)


def paraphrase(instruction: str, rng: np.random.Generator, names=()) -> str:
    """Return the instruction reworded at random; words in `names` are kept as they are."""
    words, out, i = tokenize(instruction), [], 0
    while i < len(words):
        for canon, wordings in _CANONICAL:
            n = len(canon)
            if tuple(words[i:i + n]) == canon and not set(words[i:i + n]) & set(names):
                choice = int(rng.integers(len(wordings) + 1))
                out += list(canon if choice == len(wordings) else wordings[choice])
                i += n
                break
        else:
            out.append(words[i])
            i += 1
        if out and out[-1] in COUNTS and rng.random() < 0.5:
            out.append(UNIT_WORDS[rng.integers(len(UNIT_WORDS))])
    opening = OPENINGS[rng.integers(len(OPENINGS))]
    closing = CLOSINGS[rng.integers(len(CLOSINGS))]
    return ' '.join(w for w in (opening, *out, closing) if w)


def paraphrased(data: GroundingSet, share: float, seed: int) -> GroundingSet:
    """
    Return `data` with `share` of its instructions reworded (paraphrase), its names kept.

    A training augmentation: the model learns the wordings themselves, as the human data's
    annotators use some of them ("the left most tree"); the Grounder still reads a user's
    wording into the model's words. Its own generator, so the worlds are the same at any share.
    """
    if not share:
        return data
    rng = np.random.default_rng([seed, 3])
    names = {w for name in data.entities.names for w in name.split('_')}
    instructions = [
        paraphrase(text, rng, names) if rng.random() < share else text
        for text in data.instructions
    ]
    return replace(data, instructions=instructions)


# cell sizes a robot's map has (metres): the metric suite draws one per instruction
CELL_SIZES = (0.05, 0.1, 0.25, 0.5, 1.0)


def say_metres(metres: float, rng: np.random.Generator) -> str:
    """Return a distance as people say it: '0.5 metres', '50 cm', '2 m', 'two meters'."""
    if metres < 1 and rng.random() < 0.5:
        return f'{round(metres * 100)} cm'
    number = f'{metres:g}'
    words = {1.0: 'one', 2.0: 'two', 3.0: 'three', 4.0: 'four'}
    if metres in words and rng.random() < 0.5:
        number = words[metres]
    unit = ('metres', 'meters', 'm')[rng.integers(3)]
    if metres == 1.0 and unit != 'm':
        unit = unit[:-1]
    return f'{number} {unit}'


def in_metres(instruction: str, rng: np.random.Generator) -> tuple[str, float]:
    """
    Return the instruction with each count of cells said in metres, and the cell size drawn.

    "reach cell two below rock" on 0.25 m cells: "reach cell 0.5 metres below rock".
    """
    cell_size = float(CELL_SIZES[rng.integers(len(CELL_SIZES))])
    words = [
        say_metres(NUMBERS[w] * cell_size, rng) if w in COUNTS else w
        for w in tokenize(instruction)
    ]
    return ' '.join(words), cell_size
