# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The steps of a several-step request, in the order they are meant (reading.py's intent).

"the fridge, then the sofa" is two steps in the order said; "the sofa after the fridge",
"the sofa, but first the fridge" and "before the sofa, the fridge" are the same two in the
other order; "the fridge before the sofa", "the fridge and the sofa" and "go to the fridge
and go to the sofa" are two in the order said. Each step must name a landmark, and a later
step said of the one before ("then to the horse on the left in that row") leaves the words
one step: the network reads them.
"""

from __future__ import annotations

from typing import Callable

from .checks import DIRECTIONS
from .clauses import bare, listed, placed, PLACING_VERBS
from .phrases import find_phrase
from .vocabulary import GO_VERBS, SEQUENCE_MARKS

# marks before the step to take first: "the sofa after the fridge"
EARLIER_MARKS = (
    'but first', 'but before that', 'before that', 'after visiting', 'after going to',
    'after you go to', 'after you have been to', 'after',
)
# marks before the step to take second: "the fridge before the sofa"
LATER_MARKS = (
    'before going to', 'before you go to', 'before heading to', 'before you head to',
    'before visiting', 'before',
)
# a step said of the one before
BACK_REFERENCES = frozenset('that there it its those'.split())
# ... but not what a step carries: "and bring it to the sofa", "and put it on the desk"
CARRY_VERBS = frozenset('bring take carry deliver'.split()) | PLACING_VERBS


def steps(words: list[str], mentions: Callable[[list[str]], list]) -> list[list[str]]:
    """Return the steps of the words in the order meant, or the words as one step."""
    marks = find_phrase(words, SEQUENCE_MARKS)
    if marks:
        cuts, start = [], 0
        for i, p in marks:
            cuts.append(words[start:i])
            start = i + len(p.split())
        cuts = [c[1:] if c[:1] == ['first'] else c for c in [*cuts, words[start:]]]
        cuts = [[w for w in c if w != 'and'] if c[-1:] == ['and'] else c for c in cuts if c]
        # "then the sofa and the lamp": a list of places within a step is that many steps
        cuts = [place for c in cuts for place in listed(c, mentions) or [c]]
        cuts = on_the_way(cuts, mentions)
        if len(cuts) == 1:
            return cuts
        return said_of_it(cuts, mentions) or checked(cuts, words, mentions)
    for i, p in find_phrase(words, EARLIER_MARKS):
        if i > 0:  # "go to the sofa after the fridge": the fridge first
            return checked([trimmed(words[i + len(p.split()):]), trimmed(words[:i])], words,
                           mentions)
    for i, p in find_phrase(words, LATER_MARKS):
        if i > 0:  # "go to the fridge before the sofa": in the order said
            return checked([trimmed(words[:i]), trimmed(words[i + len(p.split()):])], words,
                           mentions)
    places = listed(words, mentions)  # "the fridge and the couch"
    if places:
        return checked(places, words, mentions)
    # "go to the fridge and go to the couch": each part a place of its own
    ands = [i for i, w in enumerate(words[:-1])
            if w == 'and' and words[i + 1] in GO_VERBS | PLACING_VERBS]
    if ands:
        bounds = [0, *ands, len(words)]
        cuts = on_the_way([trimmed(words[a:b]) for a, b in zip(bounds, bounds[1:])], mentions)
        if len(cuts) == 1:
            return cuts
        one = said_of_it(cuts, mentions)
        if one or checked(cuts, words, mentions) is cuts:
            return one or cuts
    opener = words[0] if words else None
    if opener in ('after', 'before'):  # "after the fridge, go to the sofa"
        rest = words[1:]
        # the commas are gone by now: the request's go verb opens the step said second
        cut = next((j for j, w in enumerate(rest) if j and w in GO_VERBS), None)
        if cut is not None:
            first, then = rest[:cut], rest[cut:]
            said = [first, then] if opener == 'after' else [then, first]
            return checked([trimmed(c) for c in said], words, mentions)
    return [words]


def on_the_way(cuts: list[list[str]], mentions) -> list[list[str]]:
    """
    Return the cuts but a placing or a leaving that says no place, when another remains.

    "put the cup down, then go to the sofa", "leave the sofa and go to the fridge": it is
    done where the robot is, no place to go to. Said alone, the reading declines it.
    """
    kept = [c for c in cuts if placed(c, mentions) is not None]
    return kept or cuts


def checked(cuts: list[list[str]], words: list[str], mentions) -> list[list[str]]:
    """Return the cuts as steps if each names a landmark and none is said of another."""
    if len(cuts) < 2 or not all(cuts) or not all(mentions(c) for c in cuts):
        return [words]
    if any(w in BACK_REFERENCES and c[k - 1:k] not in ([v] for v in CARRY_VERBS)
           for c in cuts[1:] for k, w in enumerate(c)):
        return [words]
    return cuts


def said_of_it(cuts: list[list[str]], mentions) -> list[list[str]] | None:
    """
    Return the steps of "go to the fridge, then stop two right of it", or None.

    The second step is said of the landmark the first names and names none of its own: "it"
    is that landmark. After the landmark itself ("go to the fridge") the place said of it is
    where the robot ends up, one step; after a place beside it ("go above the rock, then
    below it"), two steps.
    """
    if len(cuts) != 2:
        return None
    first, then = cuts
    named = mentions(first)
    if len(named) != 1 or mentions(then) or 'it' not in then or 'its' in then:
        return None
    landmark = ['the', *named[0].words]
    then = [x for w in then for x in (landmark if w == 'it' else [w])]
    if bare(first, named):
        return [then]
    sides = [w for k, w in enumerate(first) if w in DIRECTIONS and first[k + 1:k + 2] != ['to']]
    return [first, then] if sides else None


def trimmed(cut: list[str]) -> list[str]:
    """Return a step's words without 'and' and 'first' at its ends."""
    while cut and cut[0] in ('first', 'and'):
        cut = cut[1:]
    while cut and cut[-1] == 'and':
        cut = cut[:-1]
    return cut
