# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Why an instruction has no answer on a map, where the table and the map already say so.

Each check reads the landmarks an instruction names (lexicon.Mention), the map and the
words, and returns a reason or None:

- `referent-missing: rock`: a named landmark is not on the map;
- `unknown-landmark: fridge`: a word where a landmark's name goes is no kind of the table
  and no word the model knows;
- `off-map`: the cell named lies past the map's edge ("four below the house" on the row
  above the bottom one);
- `ambiguous: 3 rocks`: the one landmark named is one the map holds more than once, with
  nothing that picks one ("below the rock", but not "below the westernmost rock" or "the
  rock in the top row"); and `ambiguous: 2 stools tie as northernmost`, when the word that
  picks one is an extreme that two of them share.

- `ambiguous: "in front of" names no side on a map`: in front of and behind depend on
  which way the landmark faces, which the map does not say.
- `goal-on-obstacle`: the one landmark named, held once, has its named offset on an
  obstacle.

The model's own doubt (`low-confidence`), and a goal it puts on an obstacle, are the
grounder's to judge, after it has grounded.
"""

from __future__ import annotations

import re

import numpy as np

from .lexicon import (
    count_objects,
    EXTREME_WORDS,
    FILLER_WORDS,
    Mention,
    RELATION_WORDS,
)
from .places import FAR_WORDS
from .vocabulary import GO_VERBS
from ..core.entities import EntityTable
from ..core.footprints import anchor, footprints, side_of

NUMBERS = {
    **{
        w: n
        for n, w in enumerate(
            'one two three four five six seven eight nine ten eleven twelve'.split(), 1
        )
    },
    **{str(n): n for n in range(1, 100)},
}
# one step in each direction a word names (row 0 is north)
DIRECTIONS = {
    **dict.fromkeys('above over up north top upper'.split(), (-1, 0)),
    **dict.fromkeys('below under beneath underneath down south bottom lower'.split(), (1, 0)),
    **dict.fromkeys('left west'.split(), (0, -1)),
    **dict.fromkeys('right east'.split(), (0, 1)),
    'northeast': (-1, 1),
    'northwest': (-1, -1),
    'southeast': (1, 1),
    'southwest': (1, -1),
}
# an extreme before a name ("the topmost stool") -> (axis, sign): the landmark with the
# largest sign * coordinate of its edge on that axis (row 0 is north)
EXTREME_SIDES = {
    **dict.fromkeys(
        'northernmost northmost topmost uppermost upmost highest top upper northern'.split(),
        (0, -1),
    ),
    **dict.fromkeys(
        'southernmost southmost bottommost lowermost lowest bottom lower southern'.split(), (0, 1)
    ),
    **dict.fromkeys('westernmost westmost leftmost left western'.split(), (1, -1)),
    **dict.fromkeys('easternmost eastmost rightmost right eastern'.split(), (1, 1)),
}
# direction words that describe a landmark when they stand right before its name
ADJECTIVES = frozenset('left right top bottom upper lower'.split())
# words before a name that pick one of several ("the left horse", "the second tree")
QUALIFIERS = EXTREME_WORDS | frozenset(
    'left right top bottom upper lower middle first second third last farthest furthest '
    'closest nearest only single lone most northern southern eastern western upmost westmost '
    'eastmost center centre central centermost middlemost leftmost rightmost '
    'topmost uppermost bottommost lowermost highest lowest west east north south'.split()
)
# relations a person faces a landmark with, which a map seen from above has no side for
SIDELESS = ('in front of', 'behind', 'in back of')
# nearness words: with no kind before them to pick one of, no side and no count, every cell
# around the landmark fits ("go next to the table", read as "reach closest to the table")
NEARNESS = frozenset('closest nearest near beside'.split())
# relations the model never learned: it would read "furthest from" as closest to, and a row
# or column shared with a landmark as a cell beside it
UNLEARNED = (
    'furthest from', 'farthest from', 'furthest away from', 'farthest away from',
    'same row as', 'same column as',
)  # fmt: skip
# words that say where not to be, or a distance with no side ("go away from the fridge", "two
# cells away from it"): with no direction word, no cell to go to (the network would read them
# as closest to the landmark); with one ("one cell left, away from the fridge"), a place
AWAY = ('away from', 'far from', 'clear of', 'back from')
# the farthest of cells, not of a kind ("the farthest cell from the lamp"): never learned, and
# the network reads it as the closest
FARTHEST_CELL = re.compile(r' (?:farthest|furthest) (?:\w+ ){1,2}from ')
# words before an extreme that say it is one of several that pick the landmark together
# ("the left topmost horse", "topmost and eastmost rock", "the higher of westernmost houses",
# "the two topmost trees")
COMPOUNDING = frozenset('and or of both'.split()) | QUALIFIERS | frozenset(NUMBERS)
# words after a name that go on to say which one ("the rock in the top row", "near the tree")
CLAUSES = RELATION_WORDS | frozenset('in on at of with that which by from farthest'.split())
# words after a name that end its phrase
PHRASE_ENDS = frozenset('and then please thanks now there here first'.split())
# the map itself, never a landmark
MAP_WORDS = frozenset('map grid board world field floor ground room'.split())
ARTICLES = frozenset('the a an'.split())
# words before an unknown word that put it where a landmark's name goes
BEFORE_A_NAME = frozenset(
    'the a an of to with from near by beside between and reach closest nearest'.split()
) | frozenset(DIRECTIONS)


def offset_before(words: list[str], start: int, end: int) -> tuple[int, int]:
    """
    Sum the steps the words [start, end) say: "two to the right and one below" is (1, 2).

    A number counts for the next direction word; a direction with no number is one step. A
    word such as "left" right before the name ("the left horse") picks a landmark and is no
    step.
    """
    said = [i for i in range(start, end) if words[i] not in FILLER_WORDS]
    if said and words[said[-1]] in ADJECTIVES:
        end = said[-1]
    dr = dc = 0
    count, pair, pair_count = None, None, 1
    for w in words[start:end]:
        if w in NUMBERS:
            count, pair = NUMBERS[w], None
        elif w in DIRECTIONS:
            step = DIRECTIONS[w]
            if pair is not None and 0 in pair and (pair[0] == 0) != (step[0] == 0):
                # "two cells north east": the count goes with both words of a diagonal
                n = pair_count
                dr, dc, pair = dr + n * step[0], dc + n * step[1], None
                continue
            n = 1 if count is None else count
            dr, dc, count = dr + n * step[0], dc + n * step[1], None
            pair, pair_count = step, n
        else:
            pair = None
    return dr, dc


# nouns that name no kind: "the leftmost object" could be any landmark's
GENERIC_NOUNS = frozenset('object objects thing things item items landmark landmarks'.split())


def kindless_pick(words: list[str]) -> str | None:
    """Return why "the leftmost object" (an extreme of no kind) names no landmark, or None."""
    picked = next((w for k, w in enumerate(words)
                   if w in GENERIC_NOUNS and k and words[k - 1] in QUALIFIERS), None)
    return picked and f'ambiguous: "{picked}" names no kind of landmark to pick one of'


def particle(words: list[str], i: int) -> bool:
    """
    Say whether words[i] is a verb's particle, no side: "walk over to", "go up to the door".

    "Over" right before "to" is one ("one over to the left": one to the left); "up" or "down"
    there too, unless a side follows ("two down to the left" is down and left); another
    side word is a side ("left to the rock").
    """
    if words[i] not in ('over', 'up', 'down') or words[i + 1:i + 2] != ['to']:
        return False
    after = [w for w in words[i + 2:i + 4] if w not in ('the', 'a')][:1]
    return words[i] == 'over' or not after or after[0] not in DIRECTIONS


def opposite_sides(words: list[str], mentions: list[Mention]) -> str | None:
    """
    Return why one landmark said with steps on both sides of an axis fits no cell, or None.

    "one above the rock and two below": the steps before the landmark and those after its
    "and" go opposite ways along one axis. Two landmarks ("above the rock and below the
    heart") are a place between them, not this.
    """
    if len(mentions) != 1 or words[mentions[0].end:mentions[0].end + 1] != ['and']:
        return None
    sides = [(DIRECTIONS[w], i) for i, w in enumerate(words)
             if w in DIRECTIONS and not particle(words, i)]
    before = [d for d, i in sides if i < mentions[0].start]
    after = [d for d, i in sides if i > mentions[0].end]
    if any(a[k] * b[k] < 0 for a in before for b in after for k in (0, 1)):
        return 'ambiguous: the words put the goal on opposite sides of the landmark'
    return None


def mention_offsets(words: list[str], mentions: list[Mention]) -> list[tuple[Mention, tuple]]:
    """
    Pair each mention with the offset its words say: those back to the previous mention.

    "one above the star and two to the right of the circle": the star (-1, 0), the circle
    (0, 2), as a row-and-column reference means them.
    """
    pairs, previous = [], 0
    for m in mentions:
        pairs.append((m, offset_before(words, previous, m.start)))
        previous = m.end
    return pairs


def place_offsets(place, mentions: list[Mention], names) -> list[tuple[Mention, tuple]]:
    """
    Pair each mention with its offset as a typed place (places.Place) says it.

    The reading's one account of the offsets, where the grammar read every word: "two cells
    nrth-east of the lamp" is (-2, 2) from the lamp, whatever its model wording sums to.
    `names`: the table's name of each kind. A landmark the place does not name has none.
    """
    said = [(place.landmark, place.offset), (place.other, place.other_offset)]
    pairs = []
    for landmark, offset in said:
        m = next((m for m in mentions if landmark and names[m.kind] == landmark.name), None)
        if m is not None and all(m is not n for n, _ in pairs):
            pairs.append((m, offset))
    return pairs


def named_sides(
    words: list[str], mentions: list[Mention], offsets: list | None = None
) -> dict[int, tuple[int, int]]:
    """
    Return each named kind's side: the signs of its first mention's offset (footprints).

    `offsets`: the mentions' offsets as the reading has them (place_offsets); by default the
    words before each mention (mention_offsets).
    """
    sides: dict[int, tuple[int, int]] = {}
    for m, offset in mention_offsets(words, mentions) if offsets is None else offsets:
        sides.setdefault(m.kind, side_of(offset))
    return sides


def off_map(grid: np.ndarray, offsets: list[tuple[Mention, tuple]]) -> bool:
    """
    Return whether a named offset from a landmark leaves the map from each of its cells.

    `offsets` pairs each mention with its offset (mention_offsets, place_offsets): a
    row-and-column reference ("one above the star and two to the right of the circle")
    checks the row of the one and the column of the other.
    """
    h, w = grid.shape
    for m, (dr, dc) in offsets:
        if (dr, dc) == (0, 0):
            continue
        rows, cols = np.nonzero(grid == m.kind)
        if not len(rows):
            continue
        inside = np.ones(len(rows), dtype=bool)
        if dr:
            inside &= (rows + dr >= 0) & (rows + dr < h)
        if dc:
            inside &= (cols + dc >= 0) & (cols + dc < w)
        if not inside.any():
            return True
    return False


# the words of a move besides its directions and count ("go 3 cells north", "head east")
MOVE_WORDS = GO_VERBS | ARTICLES | frozenset('to towards toward and'.split())
COUNTED_UNITS = frozenset('cell cells square squares step steps space spaces tile tiles'.split())


def moves(content: list[str]) -> bool:
    """
    Say whether words that name no landmark ask for a move: directions, a count, a verb.

    "go north", "move 2 cells to the left": a move from where the robot is, which the map
    alone does not place (the network would pick a cell by the words). A cell or a corner
    ("the top left corner", "the top left cell") is a place of the map, and a number that no
    unit or direction follows, nor ends the words after one ("go up two"), is a name ("move
    the 10 above the 11": ISI's numbered blocks).
    """
    if not set(content) & set(DIRECTIONS):
        return False
    for i, w in enumerate(content):
        before, after = content[i - 1] if i else None, content[i + 1:i + 2]
        # "two cells", "two left", and last after a direction: "go up two"
        counted = (after[0] in COUNTED_UNITS or after[0] in DIRECTIONS) if after else (
            before in DIRECTIONS
        )
        if w in DIRECTIONS or w in MOVE_WORDS or (w in NUMBERS and counted):
            continue
        if w in COUNTED_UNITS and before in NUMBERS:
            continue
        return False
    return True


def relation_reason(words: list[str], place_read: bool) -> str | None:
    """
    Return why the relation the words say leaves no cell to go to, or None.

    `place_read`: whether a place's grammar read every word (a side, a kind picked farthest:
    farthest is then composed, not the network's).
    """
    text = f' {" ".join(w for w in words if not (place_read and w in FAR_WORDS))} '
    sideless = next((w for w in SIDELESS if f' {w} ' in text), None)
    if sideless:
        return f'ambiguous: "{sideless}" names no side on a map'
    unlearned = next((w for w in UNLEARNED if f' {w} ' in text), None)
    if unlearned:
        return f'unsupported: "{unlearned}" is no relation the model learned'
    farthest = None if place_read else FARTHEST_CELL.search(text)
    if farthest:
        return f'unsupported: "{farthest.group(0).strip()}" is no relation the model learned'
    away = next((w for w in AWAY if f' {w} ' in text), None)
    if away and not place_read and not set(words) & set(DIRECTIONS):
        return f'unsupported: "{away}" says where not to be, not which cell to go to'
    return None


def on_obstacle(
    table: EntityTable, grid: np.ndarray, offsets: list[tuple[Mention, tuple]]
) -> bool:
    """Return whether the one landmark named, held once, has its named offset on an obstacle."""
    if len({m.kind for m, _ in offsets}) != 1:
        return False
    (m, (dr, dc)), *_ = offsets
    cells = np.argwhere(grid == m.kind)
    if len(cells) != 1 or (dr, dc) == (0, 0):
        return False
    r, c = cells[0][0] + dr, cells[0][1] + dc
    inside = 0 <= r < grid.shape[0] and 0 <= c < grid.shape[1]
    return inside and int(grid[r, c]) in table.never_goal


def _neighbour_words(words: list[str], m: Mention) -> tuple[list[str], list[str]]:
    before = [w for w in words[:m.start] if w not in FILLER_WORDS][-1:]
    after = [w for w in words[m.end:] if w not in FILLER_WORDS][:1]
    return before, after


def _compound_extreme(words: list[str], m: Mention, mentions: list[Mention]) -> bool:
    """
    Return whether more than the extreme before a name picks the landmark.

    Another extreme before it ("topmost and leftmost tree"), a side after it ("the upmost
    rock to the right"), or the name said twice ("the horse above the easternmost horse").
    """
    kept = [w for w in words[:m.start] if w not in FILLER_WORDS]
    return (
        len(kept) > 1
        and kept[-2] in COMPOUNDING
        or bool(set(words[m.end:]) & (QUALIFIERS | set(DIRECTIONS)))
        or sum(x.kind == m.kind for x in mentions) > 1
    )


def ambiguity(
    grid: np.ndarray,
    words: list[str],
    m: Mention,
    mentions: list[Mention],
    drawn_over_cells: bool = True,
    offsets: list[tuple[Mention, tuple]] | None = None,
):
    """
    Return why the only landmark named is ambiguous, as (how many, why), or None.

    It is when the map holds it more than once and nothing picks one ((3, '')), or an
    extreme picks two or more ((2, 'tie as northernmost')). With another landmark named, the
    two together usually pick one ("the heart to the left of the horse"), so only a lone
    reference is judged. `drawn_over_cells`: the table's landmarks may cover several cells
    (EntityTable.has_footprints); if not, each cell is one for the extremes, as the grounder
    and the generator take them. `offsets`: the mentions' offsets, as map_reason takes them.
    """
    if len({x.kind for x in mentions}) > 1:
        return None
    count = count_objects(grid, m.kind)
    if count < 2:
        return None
    before, after = _neighbour_words(words, m)
    if set(after) & CLAUSES:
        return None
    if before and before[0] in EXTREME_SIDES:
        if _compound_extreme(words, m, mentions):
            return None
        # compared as the grounder compares them: each landmark at its anchor (footprints.py)
        axis, sign = EXTREME_SIDES[before[0]]
        side = named_sides(words, mentions, offsets).get(m.kind, (0, 0))
        if drawn_over_cells:
            keys = [sign * anchor(cells, side)[axis] for cells in footprints(grid, m.kind)]
        else:  # each cell one landmark, its own anchor
            keys = (sign * np.argwhere(grid == m.kind)[:, axis]).tolist()
        ties = keys.count(max(keys))
        return (ties, f'tie as {before[0]}') if ties > 1 else None
    if before and before[0] in ('nearest', 'closest'):  # "the nearest chair": near to what?
        return count, 'and no landmark named to be nearest to'
    return None if set(before) & QUALIFIERS else (count, '')


def said(table: EntityTable, kind: int) -> str:
    """Return a kind's name as words ('trash_can': 'trash can')."""
    return table.names[kind].replace('_', ' ')


def nearness_alone(words: list[str], mentions: list[Mention]) -> bool:
    """
    Say whether nearness to one landmark is all the words say of the goal.

    "go next to the table": any cell around it fits. "The rock closest to the tree" picks a
    rock, "the cell next to the triangle on the right" and "two cells near the tree" say which
    cell.
    """
    if len(mentions) != 1:
        return False
    if not NEARNESS & set(words[:mentions[0].start]):
        return False
    return not any(w in DIRECTIONS or w in NUMBERS for w in words)


def map_reason(
    table: EntityTable,
    grid: np.ndarray,
    words: list[str],
    mentions: list[Mention],
    offsets: list[tuple[Mention, tuple]] | None = None,
) -> str | None:
    """
    Return the first reason the map gives that no cell fits the words, or None.

    `words` and `mentions` are a reference as the reading gives it (reading.Reference): the
    model's wording, each landmark one word; what the words alone rule out (an unknown
    landmark, an unlearned relation, a side a map has not) the reading has judged already.
    `offsets`: each mention's offset where the reading typed the place (place_offsets); by
    default the words before each mention say it.
    """
    if offsets is None:
        offsets = mention_offsets(words, mentions)
    for m in mentions:
        if m.kind in table.obstacles:
            continue
        if not (grid == m.kind).any():
            return f'referent-missing: {said(table, m.kind)}'
    if nearness_alone(words, mentions) and mentions[0].kind not in table.solid:
        return f'ambiguous: no side of the {said(table, mentions[0].kind)} is named'
    if off_map(grid, offsets):
        return 'off-map'
    if on_obstacle(table, grid, offsets):
        return 'goal-on-obstacle'
    for m in mentions:
        found = (
            None
            if m.kind in table.obstacles
            else ambiguity(grid, words, m, mentions, table.has_footprints, offsets)
        )
        if found is not None:
            n, why = found
            return f'ambiguous: {n} {said(table, m.kind)}s' + (f' {why}' if why else '')
    return None
