# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The generator's instructions worded as people word them (our own grammar, core/wording.py).

`paraphrase` rewords a generated instruction: each phrase of core/wording.PHRASES may become
one of its other wordings, a count may gain a unit ("two squares below"), and a request may
open or close with filler ("please", "the robot should"). The landmark names are kept. The
suite measures the node on these (`suite --wording paraphrase`).
"""

from __future__ import annotations

import numpy as np

from ..core.text import tokenize
from ..core.wording import COUNTS, PHRASES

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
