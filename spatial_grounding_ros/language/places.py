# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The place an instruction names, as one typed value the generator words and the reading parses.

A `Place` is a relation to landmarks (`Landmark`: a kind's name and what picks one of several)
or to the map itself. `surface(place, style)` words it (style 0 is Janner et al.'s synthetic
grammar, word for word, for the relations the network learned from it; other styles are the
ways people say the same), and `parse(words, names)` reads a reference's words, each landmark
held as one slot, back into the Place (grammar.py), so that parse(surface(x)) == x for every
Place the generator makes (test_places.py).

A place the network did not learn (`composed`) is grounded by composing the network's
groundings of its landmarks (language/compose.py): an offset past the learned ones as a shift
of the value map, between as the midpoint, an ordinal or farthest over the map's landmarks of
the kind, a corner or an edge from the map alone.
"""

from __future__ import annotations

from dataclasses import dataclass, replace


# the four sides, as (row, col) steps; row 0 is north
SIDES = {'north': (-1, 0), 'south': (1, 0), 'west': (0, -1), 'east': (0, 1)}
# side words people use for each side of a map or of a row of landmarks
SIDE_WORDS = {
    **dict.fromkeys('north top upper up above'.split(), 'north'),
    **dict.fromkeys('south bottom lower down below'.split(), 'south'),
    **dict.fromkeys('west left'.split(), 'west'),
    **dict.fromkeys('east right'.split(), 'east'),
}
# Janner's extreme word of each side
EXTREME_OF = {
    'north': 'northernmost', 'south': 'southernmost', 'west': 'westernmost', 'east': 'easternmost'
}  # fmt: skip
# superlatives that say a side: "the second-highest tree"; "furthest left" is said as a side
SUPERLATIVES = {
    **dict.fromkeys('northernmost northmost topmost uppermost upmost highest'.split(), 'north'),
    **dict.fromkeys('southernmost southmost bottommost lowermost lowest'.split(), 'south'),
    **dict.fromkeys('westernmost westmost leftmost'.split(), 'west'),
    **dict.fromkeys('easternmost eastmost rightmost'.split(), 'east'),
}
ORDINALS = {
    **{w: k for k, w in enumerate(
        'first second third fourth fifth sixth seventh eighth ninth tenth'.split(), 1)},
    **{f'{k}{s}': k for k, s in ((1, 'st'), (2, 'nd'), (3, 'rd'))},
    **{f'{k}th': k for k in range(4, 11)},
}  # fmt: skip
ORDINAL_WORDS = {k: w for w, k in ORDINALS.items() if w.isalpha()}
# picks made among a kind's landmarks on the map (language/compose.py), not by the network
PICKED = ('ordinal', 'closest', 'farthest', 'beside')
CORNERS = ('north-west', 'north-east', 'south-west', 'south-east')
# the longest count along one axis, and along each of two, that the network learned; longer
# offsets are its grounding of the learned part, shifted by the rest (one mechanism)
LEARNED_STRAIGHT, LEARNED_TWO_AXES = 4, 2
UNIT_WORDS = frozenset(
    'cell cells square squares step steps space spaces tile tiles spot spots'.split()
)
MAP_NOUNS = frozenset('map grid room area world board floor space'.split())
EDGE_NOUNS = frozenset('wall edge side border'.split())
NEAR_WORDS = frozenset('closest nearest'.split())
# the anchor of a nearest said of nothing else ("the nearest chair"): the robot's cell
ROBOT = 'robot'
FAR_WORDS = frozenset('farthest furthest'.split())
MIDDLE_WORDS = frozenset('middle centre center midpoint'.split())
HALFWAY_WORDS = frozenset('halfway midway midpoint'.split())
ANY_WORDS = frozenset('any either whichever'.split())  # "any chair": the nearest the robot
# the words a place's grammar reads besides slots, counts and directions (reading.py knows them)
PLACE_WORDS = (
    frozenset(ORDINALS) | frozenset(SUPERLATIVES) | UNIT_WORDS | MAP_NOUNS | EDGE_NOUNS
    | NEAR_WORDS | FAR_WORDS | MIDDLE_WORDS | HALFWAY_WORDS | ANY_WORDS
    | frozenset('corner between from of to the a and away with cell counting diagonally point spot'
                .split())
)  # fmt: skip


@dataclass(frozen=True)
class Landmark:
    """
    One landmark as said: the table's name of its kind, and what picks one of several.

    `pick`: None (the only one), 'extreme' (the one furthest to `side`), 'ordinal' (the
    `rank`-th counted from `side`), 'closest' or 'farthest' (from `anchor`), 'beside' (the
    nearest on `side` of `anchor`).
    """

    name: str
    pick: str | None = None
    side: str | None = None
    rank: int = 1
    anchor: 'Landmark | None' = None


@dataclass(frozen=True)
class Place:
    """
    A place an instruction names. Offsets are (rows, cols); row 0 is north.

    - 'landmark': `offset` from `landmark` ((0, 0): the landmark's own cell);
    - 'between': the midpoint of `landmark` and `other`, on the sides `offset` and
      `other_offset` of each if they are not (0, 0) ("left of the horse and right of the heart");
    - 'both': the cell at `offset` from `landmark` and at `other_offset` from `other`;
    - 'row-col': the row `offset` from `landmark`, the column `other_offset` from `other`;
    - 'corner': the map's corner `side` ('north-west' ...);
    - 'edge': the middle of the map's side `side` ('east' ...);
    - 'robot': the robot's cell when the instruction came ("go to the fridge and come back").

    `on`: a landmark named on the goal cell ("reach rock between star and circle").
    """

    relation: str
    landmark: Landmark | None = None
    offset: tuple[int, int] = (0, 0)
    other: Landmark | None = None
    other_offset: tuple[int, int] = (0, 0)
    side: str | None = None
    on: str | None = None


def learned_offset(offset: tuple[int, int], landmark: Landmark | None = None) -> bool:
    """
    Say whether the network learned an offset from a landmark said this way.

    From a landmark of its own: Janner's offsets and ours (generator.FAMILY_OFFSETS); from an
    extreme: one step along an axis (Janner's global phrasing); from a closest: none.
    """
    dr, dc = map(abs, offset)
    pick = None if landmark is None else landmark.pick
    if pick == 'extreme':
        return dr + dc <= 1
    if pick is not None:
        return offset == (0, 0)
    if 0 in (dr, dc):
        return max(dr, dc) <= LEARNED_STRAIGHT
    return max(dr, dc) <= LEARNED_TWO_AXES and (max(dr, dc) == 2 or (dr, dc) == (1, 1))


def learned_part(offset: tuple[int, int], landmark: Landmark | None = None) -> tuple[int, int]:
    """
    Return the part of an offset the network reads; the rest shifts its value map.

    All of a learned offset; of any other, none: the network grounds the landmark itself, the
    cell it is surest of (a part of the offset could end on a puddle or beside another
    landmark, where it is less sure: 92-94% on compound offsets against 99%+).
    """
    return offset if learned_offset(offset, landmark) else (0, 0)


def learned(place: Place) -> tuple[Place, tuple[int, int]]:
    """Return a place as the network learned it, and the rest of its offset to shift its map by."""
    if place.relation != 'landmark':
        return place, (0, 0)
    part = learned_part(place.offset, place.landmark)
    return replace(place, offset=part), (place.offset[0] - part[0], place.offset[1] - part[1])


def learned_counts(place: Place) -> bool:
    """Say whether a row-col place's counts are ones the network learned (Janner's, to 4)."""
    return max(map(abs, (*place.offset, *place.other_offset))) <= max(_NUMBER)


def composed(place: Place) -> bool:
    """Say whether a place is grounded by composing the network's groundings (not read whole)."""
    if place.relation in ('between', 'both', 'corner', 'edge', 'robot'):
        return True
    if place.relation == 'row-col':
        return not learned_counts(place)
    return not learned_offset(place.offset, place.landmark) or composed_landmark(place.landmark)


def janner_says(place: Place) -> bool:
    """Say whether Janner's grammar words a landmark place (the network learned it from it)."""
    lm = place.landmark
    simple = lm.anchor is None or (lm.anchor.pick is None and lm.anchor.anchor is None)
    return lm.pick in (None, 'extreme', 'closest') and simple and learned_offset(place.offset, lm)


def composed_landmark(landmark: Landmark | None) -> bool:
    """Say whether picking a landmark needs more than the network (an ordinal, a farthest)."""
    if landmark is None:
        return False
    if landmark.pick in PICKED:
        return True
    return composed_landmark(landmark.anchor)


# -- surface: a Place in words ------------------------------------------------------------
_NUMBER = {1: 'one', 2: 'two', 3: 'three', 4: 'four'}
# Janner's one-step phrases
_ONE_STEP = {
    (0, -1): 'to left of', (0, 1): 'to right of', (-1, 0): 'on top of', (1, 0): 'on bottom of',
    (-1, -1): 'to top left of', (-1, 1): 'to top right of',
    (1, -1): 'to bottom left of', (1, 1): 'to bottom right of',
}  # fmt: skip
_STRAIGHT_SIDE = {
    (-1, 0): 'above', (1, 0): 'below', (0, -1): 'to the left of', (0, 1): 'to the right of'
}
_COMPASS = {(-1, 0): 'north', (1, 0): 'south', (0, -1): 'west', (0, 1): 'east'}
_PLAIN = {(-1, 0): 'up', (1, 0): 'down', (0, -1): 'left', (0, 1): 'right'}
_VERTICAL_ADJ = {-1: 'above', 1: 'below'}
_CORNER_WORDS = {
    'north-west': ('north-west', 'top left', 'upper left'),
    'north-east': ('north-east', 'top right', 'upper right'),
    'south-west': ('south-west', 'bottom left', 'lower left'),
    'south-east': ('south-east', 'bottom right', 'lower right'),
}
_EDGE_WORDS = {
    'north': ('north', 'top'), 'south': ('south', 'bottom'),
    'west': ('west', 'left'), 'east': ('east', 'right'),
}  # fmt: skip
_FROM_THE = {'north': 'top', 'south': 'bottom', 'west': 'left', 'east': 'right'}
_ORDINAL_SUPERLATIVE = {
    'north': 'highest', 'south': 'lowest', 'west': 'leftmost', 'east': 'rightmost'
}
# how many ways `surface` words each kind of place (style 0 .. n-1)
STYLES = {
    'janner': 1, 'diagonal': 4, 'compound': 3, 'long-offset': 3, 'between': 4, 'ordinal': 3,
    'farthest': 3, 'nearest': 3, 'corner': 3, 'edge': 3,
}  # fmt: skip


def _count(n: int) -> str:
    return _NUMBER.get(n, str(n))


def _cells(n: int) -> str:
    return f'{_count(n)} cell' if n == 1 else f'{_count(n)} cells'


def janner_offset(offset: tuple[int, int]) -> str:
    """Return Janner's words for a learned offset, before the landmark ('two above')."""
    dr, dc = offset
    if offset in _ONE_STEP:
        return _ONE_STEP[offset]
    if 0 in offset:
        n, step = max(abs(dr), abs(dc)), (dr and dr // abs(dr), dc and dc // abs(dc))
        return f'{_NUMBER[n]} {_STRAIGHT_SIDE[step]}'
    horizontal = f'{_NUMBER[abs(dc)]} to the {"left" if dc < 0 else "right"}'
    vertical = f'{_NUMBER[abs(dr)]} {"above" if dr < 0 else "below"}'
    return f'{horizontal} and {vertical}'


def row_col_words(offset: tuple[int, int]) -> str:
    """Return Janner's words for a row-col part: a count even of one ('one above')."""
    dr, dc = offset
    if dr:
        return f'{_NUMBER[abs(dr)]} {_VERTICAL_ADJ[dr // abs(dr)]}'
    return f'{_NUMBER[abs(dc)]} to the {_PLAIN[(0, dc // abs(dc))]} of'


def landmark_words(landmark: Landmark, style: int = 0) -> str:
    """Return a landmark's words: Janner's (style 0, no articles) or as people say it."""
    name = landmark.name
    if landmark.pick is None:
        return name if style == 0 else f'the {name}'
    if landmark.pick == 'extreme':
        return f'{EXTREME_OF[landmark.side]} {name}' if style == 0 else (
            f'the {EXTREME_OF[landmark.side]} {name}')
    if landmark.pick == 'closest':
        anchor = landmark_words(landmark.anchor, style)
        return [f'{name} closest to {anchor}', f'the {name} nearest {anchor}',
                f'the {name} closest to {anchor}'][style % 3]
    if landmark.pick == 'farthest':
        anchor = landmark_words(landmark.anchor, max(style, 1))
        return [f'the {name} farthest from {anchor}', f'the {name} furthest away from {anchor}',
                f'the furthest {name} from {anchor}'][style % 3]
    if landmark.pick == 'beside':  # "the heart to the left of the horse", "... top left of ..."
        anchor = landmark_words(landmark.anchor, max(style, 1))
        far = f'{_cells(landmark.rank)} ' if landmark.rank > 1 else ''  # "two cells left of"
        if landmark.side in SIDES:
            return f'the {name} {far}{_STRAIGHT_SIDE[SIDES[landmark.side]]} {anchor}'
        corner = ' '.join(_FROM_THE[s] for s in landmark.side.split('-'))  # 'top left'
        return f'the {name} {far}to the {corner} of {anchor}'
    if landmark.pick == 'ordinal':
        k = ORDINAL_WORDS[landmark.rank]
        side = landmark.side
        return [f'the {k} {name} from the {_FROM_THE[side]}',
                f'the {k} {_ORDINAL_SUPERLATIVE[side]} {name}',
                f'the {k} {name} counting from the {_FROM_THE[side]}'][style % 3]
    raise ValueError(f'unknown pick {landmark.pick!r}')


def side_words(offset: tuple[int, int], counted: bool = True) -> str:
    """Return an offset along one axis, before a landmark: 'two to the left of'."""
    dr, dc = offset
    n, step = max(abs(dr), abs(dc)), (dr and dr // abs(dr), dc and dc // abs(dc))
    return f'{_count(n)} {_STRAIGHT_SIDE[step]}' if counted or n > 1 else _STRAIGHT_SIDE[step]


def _offset_words(offset: tuple[int, int], style: int) -> str:
    """People's words for an offset, before "of the <landmark>" (diagonal, compound, long)."""
    dr, dc = offset
    if 0 in offset:  # along one axis
        n, step = max(abs(dr), abs(dc)), (dr and dr // abs(dr), dc and dc // abs(dc))
        return [f'{_cells(n)} {_COMPASS[step]} of', f'{n} squares {_STRAIGHT_SIDE[step]}',
                side_words(offset)][style % 3]
    v, h = (dr // abs(dr), 0), (0, dc // abs(dc))
    if abs(dr) == abs(dc):  # a diagonal
        n = abs(dr)
        compass = f'{_COMPASS[v]}-{_COMPASS[h]}'
        both = f'{_VERTICAL_ADJ[v[0]]}-{_PLAIN[h]}'
        if n == 1:
            return [f'one cell {compass} of', f'diagonally {both} of',
                    f'{_PLAIN[v]} and to the {_PLAIN[h]} of', f'one step {compass} of'][style % 4]
        return [f'{_cells(n)} {compass} of', f'{_cells(n)} diagonally {both} of',
                f'{_count(n)} {_PLAIN[v]} and {_count(n)} to the {_PLAIN[h]} of',
                f'{n} steps {compass} of'][style % 4]
    return [f'{_count(abs(dc))} {_PLAIN[h]} and {_count(abs(dr))} {_PLAIN[v]} from',
            f'{_cells(abs(dc))} to the {_PLAIN[h]} and {_cells(abs(dr))} {_STRAIGHT_SIDE[v]}',
            f'{_count(abs(dr))} {_COMPASS[v]} and {_count(abs(dc))} {_COMPASS[h]} of'][style % 3]


def surface(place: Place, style: int = 0) -> str:
    """
    Return a place in words, in one of the ways people say it (STYLES).

    Style 0 is Janner's grammar where the network learned the place from it.
    """
    if place.relation == 'corner':
        words = _CORNER_WORDS[place.side][style % 3]
        return [f'go to the {words} corner', f'the {words} corner of the map',
                f'go to the {words} corner of the room'][style % 3]
    if place.relation == 'edge':
        side = _EDGE_WORDS[place.side][style % 2]
        return [f'go to the middle of the {side} wall',
                f'the middle of the {side} edge of the map',
                f'the centre of the {side} side of the room'][style % 3]
    target = place.on or 'cell'
    if place.relation == 'between':
        a, b = place.landmark, place.other
        if style == 0:
            return f'reach {target} between {landmark_words(a)} and {landmark_words(b)}'
        a, b = landmark_words(a, 1), landmark_words(b, 1)
        return [f'go halfway between {a} and {b}', f'go to the midpoint between {a} and {b}',
                f'the cell midway between {a} and {b}'][(style - 1) % 3]
    if place.relation == 'row-col':  # Janner's: "one above star and two to the left of heart"
        vertical = row_col_words(place.offset)
        horizontal = row_col_words(place.other_offset)
        return (f'reach {target} {vertical} {landmark_words(place.landmark)} and '
                f'{horizontal} {landmark_words(place.other)}')
    landmark, offset = place.landmark, place.offset
    if style == 0 and janner_says(place):
        if offset == (0, 0):
            if landmark.pick is None:
                return f'reach cell with {landmark.name}'
            return f'reach {landmark_words(landmark)}'
        if landmark.pick == 'extreme':
            return f'reach the cell {_STRAIGHT_SIDE[offset]} the {landmark_words(landmark)}'
        return f'reach cell {janner_offset(offset)} {landmark_words(landmark)}'
    said = landmark_words(landmark, max(style, 1))
    if offset == (0, 0):
        return f'go to {said}'
    return f'go {_offset_words(offset, style)} {said}'
