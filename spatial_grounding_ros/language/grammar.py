# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The grammar of a place: a reference's words, each landmark one slot, read back into a Place.

The grammar, in one place:

    place    := offset? landmark ("and" offset)? | between | row-col | corner | edge
    offset   := (count unit? direction+ ("and")?)+ ("of" | "from" | "to")?
    landmark := slot | extreme slot | ordinal slot "from the" side | ordinal-superlative slot
              | slot ("closest" | "nearest") "to"? landmark | "the"? slot "farthest from" slot
              | slot side-word "of"? landmark   (the one on that side of it)
              | slot ("on" | "at" | "in") side-word "side"?   (the one farthest that way)
              | ("nearest" | "any" | "either" | "whichever") slot   (the one nearest the robot)
    between  := slot? ("halfway" | "midway" | "the midpoint")? "between" slot "and" slot
              | ("halfway" | "midway") "to" landmark   (from the robot's cell)
    row-col  := slot? offset slot "and" offset slot
    corner   := side side "corner" ("of the" map-word)?
    edge     := ("middle" | "centre") "of the" side ("wall" | "edge" | "side") ("of the" map)?

Parsing is conservative: a reference with a word the grammar does not account for gives
None, and the network reads its words as they are (what people say is wider than any
grammar). Why a table of word classes and a few patterns, not a parsing library: the grammar
is small, it must skip the glue words people put anywhere ("the", "to", "of"), and a
reading is asked for on every new instruction, well under a millisecond.
"""

from __future__ import annotations

import functools

from .checks import ADJECTIVES, DIRECTIONS, NUMBERS, particle
from .places import (
    ANY_WORDS,
    EDGE_NOUNS,
    FAR_WORDS,
    HALFWAY_WORDS,
    Landmark,
    MAP_NOUNS,
    MIDDLE_WORDS,
    NEAR_WORDS,
    ORDINALS,
    Place,
    ROBOT,
    SIDE_WORDS,
    SUPERLATIVES,
    UNIT_WORDS,
)
from .vocabulary import GO_VERBS, PARTICLES
from ..core.footprints import side_of

INTENSIFIERS = frozenset('right just directly straight'.split())
_COMPASS = frozenset('north south east west'.split())
OFFSET_GLUE = frozenset('the to and diagonally on of from away'.split())
_VERB_TO = [[w, 'to'] for w in PARTICLES]
# what the place is called before a between: "the point halfway between"
PLACE_NOUNS = frozenset('the a cell square spot point place location position'.split())
_OPENING = frozenset('reach go to the a cell find get move head navigate drive please'.split())


def _side_pair(words: list[str]) -> str | None:
    """Return the corner two side words name ("top left", "north-west"), or None."""
    sides = [SIDE_WORDS.get(w) for w in words]
    if len(sides) == 1 and words[0] in ('northwest', 'northeast', 'southwest', 'southeast'):
        return f'{words[0][:5]}-{words[0][5:]}'
    if len(sides) != 2 or None in sides:
        return None
    vertical = next((s for s in sides if s in ('north', 'south')), None)
    horizontal = next((s for s in sides if s in ('west', 'east')), None)
    return f'{vertical}-{horizontal}' if vertical and horizontal else None


# the side an offset's signs say, for a landmark said on a side of another
_SIDE_OF_STEP = {
    (-1, 0): 'north', (1, 0): 'south', (0, -1): 'west', (0, 1): 'east',
    (-1, -1): 'north-west', (-1, 1): 'north-east', (1, -1): 'south-west', (1, 1): 'south-east',
}  # fmt: skip


def _beside(name: str, head: list[str], rest: list[str], names: dict) -> Landmark | None:
    """
    Return "<name> <head> <rest>" as the landmark of a kind on a side of another, or None.

    The side's words come first, an offset along one axis or a diagonal, the other landmark's
    after ("left of | the bottom house"). The offset's count ("the house 5 above the horse")
    is how far: the landmark's `rank`.
    """
    for k in range(1, len(head) + 1):
        said = [w for w in head[:k] if w not in SIDE_GLUE]
        if said[:1] == ['over'] and len(said) > 1:  # "over on the left side of": a particle
            said = said[1:]
        offset = parse_offset(said)
        if offset is None or (0 not in offset and abs(offset[0]) != abs(offset[1])):
            continue
        anchor = _landmark(head[k:] + rest, names)
        # of its own kind it is Janner's cell beside it: "the horse above the easternmost horse"
        if anchor is not None and anchor.name != name:
            side = _SIDE_OF_STEP[side_of(offset)]
            return Landmark(name, 'beside', side, max(map(abs, offset)), anchor=anchor)
    return None


def parse_offset(words: list[str]) -> tuple[int, int] | None:
    """
    Return the offset the words say, or None if a word is no part of one.

    "two cells north east" is (-2, 2) (a count goes with both words of a diagonal); "three
    right and two down" is (2, 3); a direction with no count is one step.
    """
    dr = dc = 0
    count, i, seen = None, 0, False
    kept = [w for i, w in enumerate(words) if w not in OFFSET_GLUE and not particle(words, i)]
    while i < len(kept):
        w = kept[i]
        if w in INTENSIFIERS and kept[i + 1:i + 2] and DIRECTIONS.get(kept[i + 1], (0, 0))[0]:
            pass  # "right above the sofa": straight above it
        elif w in NUMBERS and count is None:
            count = NUMBERS[w]
        elif w in UNIT_WORDS:
            pass
        elif w in DIRECTIONS:
            step = DIRECTIONS[w]
            if i + 1 < len(kept) and kept[i + 1] in DIRECTIONS:  # "north east", "top left"
                nxt = DIRECTIONS[kept[i + 1]]
                if step[1] == 0 and step[0] and nxt[0] == 0 and nxt[1]:  # as compass words go
                    step = (step[0] + nxt[0], step[1] + nxt[1])
                    i += 1
            n = 1 if count is None else count
            if dr * step[0] < 0 or dc * step[1] < 0:  # "above ... below": no one offset
                return None
            dr, dc, count, seen = dr + n * step[0], dc + n * step[1], None, True
        else:
            return None
        i += 1
    return (dr, dc) if seen and count is None else None


# the robot, or the one who speaks to it (where the robot is, as for "bring me"), in "the
# chair nearest to me"
SPOKEN_TO = frozenset('me us you yourself robot'.split())
# "between the two chairs", "both chairs": two of a kind
PAIR_WORDS = frozenset('two 2 both'.split())
# said after a landmark's name, of another ("the chair near the sofa"): the one nearest it
NEAR_AFTER = (['near'], ['by'], ['beside'], ['next'], ['close'], ['closer'], ['nearer'])
# skipped in a landmark's words: "the heart that's left of the horse"
LANDMARK_GLUE = frozenset(['the', 'a', 'that', "that's", 'thats', 'which', 'is', 'one'])
# around a side word said after a landmark's name, of another ("the heart on the left side of
# the horse"): the one on that side of it
SIDE_GLUE = frozenset(
    'of on at to side directly just straight immediately located placed situated lies sits'.split()
)


def _landmark(words: list[str], names: dict[str, str]) -> Landmark | None:
    """Return the Landmark the words name (slots '@k' for landmarks), or None."""
    return _landmark_of(tuple(words), tuple(names.items()))


# each tail of a reference is read once: a landmark said of another said of another ... tries
# several splits of every tail, which read afresh took time exponential in the landmarks named
def landmark_cache_clear() -> None:
    """Forget the landmarks read so far (the bench times the reading of a new instruction)."""
    _landmark_of.cache_clear()


@functools.lru_cache(maxsize=4096)
def _landmark_of(said: tuple[str, ...], named: tuple) -> Landmark | None:
    names = dict(named)
    words = [w for w in said if w not in LANDMARK_GLUE]
    slots = [i for i, w in enumerate(words) if w in names]
    if not slots:
        return None
    first = slots[0]
    name = names[words[first]]
    before, after = words[:first], words[first + 1:]
    if len(slots) > 1:  # closest / farthest: "<name> closest to <anchor>", "farthest <name> from"
        head = after[:slots[1] - first - 1]
        anchor = _landmark(words[slots[1]:], names)
        if anchor is None:
            return None
        relation = [w for w in before + head if w not in ('to', 'from', 'away')]
        if len(relation) == 1 and relation[0] in NEAR_WORDS and before in ([], relation):
            return Landmark(name, 'closest', anchor=anchor)
        if not before and relation in NEAR_AFTER:
            return Landmark(name, 'closest', anchor=anchor)  # "the chair near the sofa"
        if not before:  # "the heart left of the horse", "... to the top left of the bottom house"
            beside = _beside(name, head, words[slots[1]:], names)
            if beside is not None:
                return beside
        if len(relation) == 1 and relation[0] in FAR_WORDS and 'from' in before + head:
            return Landmark(name, 'farthest', anchor=anchor)
        return None
    if not before and not after:
        return Landmark(name)
    # "the chair nearest to me", "the nearest chair to you", "the chair near me": the robot's
    tail = [w for w in after if w != 'to']
    if tail[-1:] and tail[-1] in SPOKEN_TO and len(before + tail) == 2 and (
        (before + tail)[0] in NEAR_WORDS or [(before + tail)[0]] in NEAR_AFTER
    ):
        return Landmark(name, 'closest', anchor=Landmark(ROBOT))
    # "the nearest chair"; "any chair", "either chair", "whichever chair is closer": the one
    # nearest the robot
    said_near = after in (['closer'], ['nearer'], ['closest'], ['nearest'])
    if before in ([w] for w in NEAR_WORDS | ANY_WORDS) and not after or (
        before in ([], *([w] for w in ANY_WORDS)) and said_near
    ):
        return Landmark(name, 'closest', anchor=Landmark(ROBOT))
    if len(before) == 1 and not after and before[0] in SUPERLATIVES:
        return Landmark(name, 'extreme', SUPERLATIVES[before[0]])
    if len(before) == 1 and not after and before[0] in ADJECTIVES:  # "the bottom house"
        return Landmark(name, 'extreme', SIDE_WORDS[before[0]])
    # "the heart on the left", "the heart, the one at the bottom", "the chair on the left side"
    if not before and after[:1] in (['on'], ['at'], ['in']) and after[2:] in ([], ['side']) and (
        after[1:2] and after[1] in ADJECTIVES | _COMPASS
    ):
        return Landmark(name, 'extreme', SIDE_WORDS[after[1]])
    if before and before[0] in ORDINALS:
        rank = ORDINALS[before[0]]
        if len(before) == 2 and before[1] in SUPERLATIVES and not after:
            side = SUPERLATIVES[before[1]]
        elif len(before) == 1 and after[:1] in (['from'], ['counting']):
            rest = [w for w in after if w not in ('from', 'counting')]
            if len(rest) != 1 or rest[0] not in SIDE_WORDS:
                return None
            side = SIDE_WORDS[rest[0]]
        else:
            return None
        if rank == 1:  # "the first from the left": the leftmost
            return Landmark(name, 'extreme', side)
        return Landmark(name, 'ordinal', side, rank)
    return None


def parse(words: list[str], names: dict[str, str]) -> Place | None:
    """
    Return the Place a reference's words name, or None if the grammar does not read them all.

    `words`: the reference's words with each landmark as one slot word; `names`: each slot
    word's landmark (the table's name of its kind).
    """
    words = _superlatives(words)
    # "the robot should walk over to ...": the place is said after the verb that opens it
    # (a verb after a count or a direction is no opening: "two go below the rock")
    said = (set(DIRECTIONS) | set(NUMBERS) | set(ORDINALS) | set(SUPERLATIVES) | set(names))
    lead = next((i for i, w in enumerate(words) if w in said), len(words))
    verbs = [i for i, w in enumerate(words[:lead]) if w in GO_VERBS]
    if verbs:
        words = words[verbs[-1] + 1:]
    words = [w for i, w in enumerate(words) if not particle(words, i)]
    while words and (words[0] in _OPENING or words[:2] in _VERB_TO) and not (
        words[0] == 'cell' and words[1:2] == ['with']
    ):
        if words[:2] in _VERB_TO:  # "go over to the couch": the verb's, no direction
            words = words[1:]
        if words[0] == 'to' and words[1:2] and words[1] in DIRECTIONS:  # "to top left of"
            break
        words = words[1:]
    if words[:2] == ['cell', 'with']:
        words = words[2:]
    if words[:1] == ['on'] and [w for w in words[1:3] if w not in ('the', 'a')][:1] in (
        [[w] for w in names]
    ):  # "on the heart left of the horse": the landmark's own cell
        words = words[1:]
    # a wall of a table that has walls is a side of the room when its middle is asked for
    sides = [names.get(w, w) if names.get(w) in EDGE_NOUNS else w for w in words]
    if not any(w in names for w in sides) and set(sides) & (MIDDLE_WORDS | {'corner'}):
        return _map_place(sides)
    slots = [i for i, w in enumerate(words) if w in names]
    if not slots:
        return None
    on = None
    # a landmark named on the goal cell: "reach rock between star and circle", "reach rock one
    # below star and two to the left of heart"
    if slots[0] == 0 and (words[1:2] == ['between'] or len(slots) == 3):
        on, words = names[words[0]], words[1:]
        slots = [i - 1 for i in slots[1:]]
    start = _landmark_start(words, slots[0])
    lead = [w for w in words[:start] if w not in PLACE_NOUNS]
    if len(slots) == 1 and lead[-1:] == ['to'] and lead[:-1] in [[w] for w in HALFWAY_WORDS]:
        landmark = _landmark(words[start:], names)  # "halfway to the fridge": from the robot
        return None if landmark is None else Place('between', Landmark(ROBOT), other=landmark)
    if 'between' in words:
        return _between(words, names, on)
    if len(slots) == 2 and 'and' in words[slots[0] + 1:slots[1]]:  # row-col
        j = words.index('and', slots[0] + 1)
        first = parse_offset(words[:slots[0]])
        second = parse_offset(words[j + 1:slots[1]])
        if first is None or second is None or words[slots[0] + 1:j]:
            return None
        opposite = first[0] * second[0] < 0 or first[1] * second[1] < 0
        if 0 in first and 0 in second and opposite:
            # "left of the horse and right of the heart": between them, on those sides; "one
            # left of the horse and two right of the heart": the cell at both offsets
            counted = any(w in NUMBERS for w in words[:slots[1]])
            return Place('both' if counted else 'between', Landmark(names[words[slots[0]]]),
                         first, Landmark(names[words[slots[1]]]), second, on=on)
        if first[1] or second[0]:
            return None
        return Place('row-col', Landmark(names[words[slots[0]]]), first,
                     Landmark(names[words[slots[1]]]), second, on=on)
    if on is not None:
        return None
    # an offset along the other axis said after the landmark: "one above the rock and one to
    # the left", "a cell above the rock and to the left"
    after = (0, 0)
    if len(slots) == 1 and words[slots[0] + 1:slots[0] + 2] == ['and']:
        after = parse_offset(words[slots[0] + 2:])
        if after is None:
            return None
        words = words[:slots[0] + 1]
    # an offset, then the landmark: the offset ends at "of"/"from"/"to"/a count's direction
    start = _landmark_start(words, slots[0])
    offset = (0, 0)
    if start:
        offset = parse_offset(words[:start])
        if offset is None or (offset[0] and after[0]) or (offset[1] and after[1]):
            return None
    landmark = _landmark(words[start:], names)
    offset = (offset[0] + after[0], offset[1] + after[1])
    return None if landmark is None else Place('landmark', landmark, offset)


# "most western": a superlative of two words, as "westernmost"
_MOST = {
    **dict.fromkeys(('west', 'western', 'left'), 'westernmost'),
    **dict.fromkeys(('east', 'eastern', 'right'), 'easternmost'),
    **dict.fromkeys(('north', 'northern', 'top', 'upper'), 'northernmost'),
    **dict.fromkeys(('south', 'southern', 'bottom', 'lower'), 'southernmost'),
}


def _superlatives(words: list[str]) -> list[str]:
    """Return the words with each "most <side>" as one superlative ("most western")."""
    out = []
    for w in words:
        if out and out[-1] == 'most' and w in _MOST:
            out[-1] = _MOST[w]
        else:
            out.append(w)
    return out


def _between(words: list[str], names: dict[str, str], on: str | None) -> Place | None:
    """Return the between place of "(halfway) between A and B", "between the two chairs"."""
    k = words.index('between')
    lead = [w for w in words[:k] if w not in PLACE_NOUNS]
    rest = words[k + 1:]
    if lead not in ([], *([w] for w in HALFWAY_WORDS), ['middle']):
        return None
    two = set(rest) & PAIR_WORDS  # said: "between horse" is no pair of horses
    if two and [w for w in rest if w not in PAIR_WORDS | {'the'}] in ([w] for w in names):
        kind = Landmark(names[rest[-1]])  # "between the two chairs": two of a kind
        return Place('between', kind, other=kind, on=on)
    if 'and' not in rest:
        return None
    j = rest.index('and')
    a, b = _landmark(rest[:j], names), _landmark(rest[j + 1:], names)
    return None if a is None or b is None else Place('between', a, other=b, on=on)


def _landmark_start(words: list[str], slot: int) -> int:
    """Return where the landmark's words begin: after the offset's last direction word."""
    i = slot
    while i > 0 and (words[i - 1] in ORDINALS or words[i - 1] in SUPERLATIVES
                     or words[i - 1] in FAR_WORDS | NEAR_WORDS | ANY_WORDS | {'the', 'a'}):
        i -= 1
    # a side word right before the name picks the landmark: "left of the bottom house"
    while i > 0 and words[i - 1] in ADJECTIVES:
        i -= 1
    # "of the", "from the": part of the offset
    return i


def _map_place(words: list[str]) -> Place | None:
    """Return a corner or an edge of the map the words name, or None."""
    words = [w for w in words if w not in ('the', 'a', 'far', 'very', 'exact')]
    tail = ['of', words[-1]] if len(words) > 2 and words[-2] == 'of' else []
    if tail and tail[1] not in MAP_NOUNS:
        return None
    body = words[: len(words) - len(tail)]
    if body[-1:] == ['corner']:
        side = _side_pair(body[:-1])
        return None if side is None else Place('corner', side=side)
    if len(body) == 4 and body[0] in MIDDLE_WORDS and body[1] == 'of' and body[3] in EDGE_NOUNS:
        side = SIDE_WORDS.get(body[2])
        return None if side is None else Place('edge', side=side)
    return None
