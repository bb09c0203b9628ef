# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The clauses around a place that are not the place (reading.py's intent reads them first).

A courtesy ("if you can", "when you are ready") asks nothing and is dropped. A condition
("if the kettle is on", "unless the door is closed") is one the robot cannot check, so the
request is declined rather than carried out as if it held. What to do on arrival ("and sit
down", "then turn left") is not where to go: its "down" and "left" say how to sit and turn,
and must not move the goal. Two landmarks joined by "or" leave the choice open: asked back.
A place set aside ("instead of the fridge", "rather than the fridge") is not the place. A
return after a place ("and come back") is one more step: back where the robot is now.
"""

from __future__ import annotations

from .checks import ARTICLES, DIRECTIONS, NUMBERS
from .phrases import find_phrase, phrase_at
from .places import UNIT_WORDS
from .vocabulary import FILLERS, GO_VERBS, MOTIONS, PARTICLES, REQUEST_OPENERS

# conditions on a request, which the robot has no sensor to check
CONDITIONS = (
    'if', 'only if', 'unless', 'when', 'whenever', 'once', 'as soon as', 'in case', 'provided',
    'providing', 'assuming', 'as long as', 'so long as', 'wait until', 'wait till',
    'wait for',
)
# how a condition on the world opens: its subject ("if the kettle ...", "unless someone ...").
# Said of the robot ("when you get a sec", "stop when you reach the fridge") it is a
# courtesy or the goal itself, which the reading reads as before.
SUBJECTS = frozenset(
    """
    the a an i we they he she it nobody noone no someone somebody anyone anybody everyone
    everybody there my your our his her their this that these those people i'm we're
    they're he's she's it's there's nobody's someone's somebody's anyone's anybody's
    everyone's
    """.split()
)
# words that take "of", whose "if" is a typo of it ("left if the tree", "the side if the box")
OF_WORDS = frozenset(DIRECTIONS) | frozenset(
    'side edge corner top bottom end front back middle centre center row column'.split()
)
# ... or the robot's seeing something ("if you see the sofa, go to the fridge")
PERCEIVING = frozenset('see spot notice find hear detect sense encounter smell'.split())
# between a place negated and the place to go ("don't go to the fridge, just go to the sofa")
JOINERS = FILLERS | frozenset('and but instead rather so then'.split())
# around a side said again ("not the right side of it")
SIDE_GLUE = frozenset('the a one on side of it to hand'.split())
# what sets a place aside for another ("the sofa instead of the fridge")
REJECTED = ('instead of', 'rather than', 'in place of', 'as opposed to')
# a return said after a place ("go to the fridge and come back"), the whole clause
RETURNS = frozenset(tuple(r.split()) for r in (
    'back', 'come back', 'come back here', 'come back to me', 'come straight back',
    'come right back', 'come back again', 'return', 'return here', 'return to me', 'go back',
    'head back', 'get back', 'back here', 'back again',
    # what is fetched, brought to the one who asked: "grab the mug ... and bring it to me"
    'bring it to me', 'bring it back', 'bring it back to me', 'bring it here', 'bring it over',
    'bring them to me', 'bring them back', 'bring them here',
))
# a courtesy worded as a condition: it holds whenever the robot is asked
COURTESIES = (
    'if you can', 'if you could', 'if possible', 'if you please', "if you don't mind",
    'if you do not mind', 'if you would', 'if you like', 'when you can', 'when possible',
    'when you are ready', "when you're ready", 'whenever you are ready',
    "whenever you're ready", 'whenever you can', 'when you get a chance',
    'whenever you get a chance', 'when you have a moment', 'when you have time',
    'as soon as possible', 'as soon as you can', 'asap', 'when you are free',
    'when you are done', "when you're done", 'when you are finished', "when you're finished",
    "if it's not too much trouble", 'if it is not too much trouble', "if it's no trouble",
    "if it's ok", "if it's okay", "if that's ok", "if that's okay", 'if ok',
)
# what a placing opens with: "put the cup on the table", "drop it off by the door"
PLACING_VERBS = frozenset('put place set drop leave deliver stash stow'.split())
# verbs of what to do on arrival ("go to the couch and sit down"); a go verb ("wait by the
# door", "stop two left of it") says where only when a landmark, "it" or a count follows it
ACTIONS = frozenset(
    """
    sit lie stand turn look slow calm settle rest sleep say tell beep ring knock listen watch
    scan check shut power lower raise hand give drop put pour wash wipe vacuum sweep hold
    relax charge dock face greet announce speak wave take grab pick fetch open close push
    pull lift carry clean play sing dance spin rotate wait stay stop pause
    """.split()
) | frozenset(m.split()[0] for m in MOTIONS) | PLACING_VERBS
# what a fetch opens with: "get a soda from the fridge"
FETCH_VERBS = frozenset('get grab pick fetch take collect bring'.split())
# ... and what says a way to go, not a thing: "get far away from the fridge"
AWAY_WORDS = frozenset(DIRECTIONS) | frozenset('away far farther further clear back off'.split())
# where a placing's place starts, after the thing placed: a relation word (a count only before
# a unit or a side: "put two cups on ..." places cups)
PLACE_OPENERS = frozenset(DIRECTIONS) | frozenset(
    'on onto in into inside at by beside next near nearby close between behind to towards '
    'toward directly just exactly right halfway'.split()
)
# ... a placing verb's particle after the thing ("set it down by", "drop it off at")
PLACING_PARTICLES = frozenset('down off up back'.split())
# ... and a place that is the landmark itself ("put it in the fridge": go to the fridge)
INTO = frozenset('on onto in into inside at'.split())
# between an action and the place before it
JOINS = ('and then', 'then', 'and', 'and also', 'after that', 'and after that')
# what may stand around a landmark in a list of places ("go to the couch and to the fridge")
BARE = GO_VERBS | FILLERS | frozenset(
    'to the a an at then also first now so me us and check'.split()
)
# ... and "by" after a verb of visiting ("stop by the lamp and the sofa"; "the circle by the
# house and the diamond" is one place)
VISIT_VERBS = GO_VERBS | frozenset('swing drop pop'.split())
# between two landmarks offered as a choice ("the fridge or maybe the couch")
CHOICE_GAP = frozenset('or the a an to maybe perhaps possibly else'.split())

# a choice of landmarks left to nearness to the robot ("whichever is closer", "the nearer of"):
# its words besides going ones, and the note a reading of one carries (Command.notes)
NEARER = frozenset('closer nearer closest nearest'.split())
NEARNESS_CHOICE = NEARER | frozenset('whichever which is one of or you'.split())
NEAREST_OF = 'nearest-of'


def without_rejected(words: list[str], mentions) -> list[str]:
    """
    Return the words without a place set aside for the one meant, if any.

    "go to the sofa instead of the fridge", "rather than the fridge, go to the sofa": the
    sofa. Set aside is the first landmark after the phrase, with the words before it.
    """
    for i, p in reversed(find_phrase(words, REJECTED)):
        rest = words[i + len(p.split()):]
        found = mentions(rest)
        kept = words[:i] + rest[found[0].end:] if found else words
        if found and mentions(kept):
            words = kept
    return words


def beside_negation(words: list[str], negation: str, mentions) -> list[str] | None:
    """
    Return the place to go said beside a negated one, or None when there is none.

    "don't go to the fridge, go to the sofa", "avoid the fridge and go to the sofa", "go to
    the sofa, but not the fridge": the sofa. The negated part runs from `negation` to the
    first landmark after it; the place to go names a landmark before it, or after it opens
    with a go verb, or is said in the negated one's place ("not the fridge, the sofa", "...
    but the sofa"); "don't go to the fridge or the sofa" has none.
    """
    [(i, _), *_] = find_phrase(words, (negation,))
    named = mentions(words[i:])
    if not named:  # "left of the fridge, not the right (side)": the side said first
        said = [w for w in words[i + len(negation.split()):] if w not in SIDE_GLUE]
        before = [w for w in words[:i] if w not in JOINERS]
        sides = said and all(w in DIRECTIONS for w in said) and set(before) & set(DIRECTIONS)
        return before if sides and mentions(before) else None
    before, after = words[:i], words[i + named[0].end:]
    joined = set()
    while after and after[0] in JOINERS:
        joined.add(after.pop(0))
    while before and before[-1] in JOINERS:
        before = before[:-1]
    # "not the sofa, the fridge", "don't go to the sofa but the fridge": said in its place
    instead = 'but' in joined or (
        negation.startswith('not') and not (i or joined or after[:1] == ['or'])
    )
    places = [p for p in (before, after) if p and mentions(p)]
    places = [p for p in places if p is before or p[0] in GO_VERBS or instead]
    return places[0] if len(places) == 1 else None


def without_fillers(words: list[str]) -> list[str]:
    """Return the words without fillers, but "the robot" said last ("closest to the robot")."""
    return [w for k, w in enumerate(words) if w not in FILLERS or (
        w == 'robot' and words[k - 1:k] == ['the'] and all(x in FILLERS for x in words[k + 1:])
    )]


def without_courtesies(words: list[str]) -> list[str]:
    """Return the words without a courtesy worded as a condition ("if you can")."""
    for i, p in reversed(find_phrase(words, COURTESIES)):
        words = words[:i] + words[i + len(p.split()):]
    return words


def condition(words: list[str]) -> str | None:
    """
    Return a condition put on the request ("if the kettle is on"), as said, or None.

    A condition opens a clause of its own, with its subject: "left if the tree" (a typo of
    "left of") and "the house thats once space to left of tree" ("one") are places. "Until"
    and "while" say how far or how to go ("move until it is left of block 14"), not when.
    """
    for i, p in find_phrase(words, CONDITIONS):
        rest = words[i + len(p.split()):]
        said_of = rest[:1] and rest[0] in SUBJECTS or rest[:1] == ['you'] and (
            rest[1:2] and rest[1] in PERCEIVING
        )
        if said_of and (i == 0 or words[i - 1] not in OF_WORDS):
            # the clause runs to the request's go verb when it opens the request, else on
            end = next((k for k, w in enumerate(rest) if w in GO_VERBS), None) if i == 0 else None
            return ' '.join([*p.split(), *rest[:end][:6]])
    return None


def without_action(words: list[str], mentions) -> tuple[list[str], str | None]:
    """
    Return the words without what to do on arrival, and that action as said (or None).

    An action is a clause after a place, joined by "and", "then" or a comma, that opens with an
    action verb and names no landmark or "it" ("and sit down", "then turn left", "and wait
    there"). "And stop two left of it" and "then stop 2 cells further north" say where.
    """
    # the commas are gone by now: "go to the couch, sit down" joins the action to the name
    unjoined = [(m.end, '') for m in mentions(words) if m.end < len(words)]
    for i, p in sorted([*find_phrase(words, JOINS), *unjoined], reverse=True):
        clause = [w for w in words[i + len(p.split()):] if w not in FILLERS]
        if not clause or clause[0] not in ACTIONS or not mentions(words[:i]):
            continue
        if clause[0] in PLACING_VERBS:  # "and put it down": "it" is the thing, put there
            if placed(clause, mentions) is None:
                return words[:i], ' '.join(clause)
            continue
        counted = any(w in NUMBERS for w in clause) and any(w in DIRECTIONS for w in clause)
        if mentions(clause) or set(clause) & {'it', 'its'} or clause[0] in GO_VERBS and counted:
            continue
        return words[:i], ' '.join(clause)
    return words, None


def fetched(words: list[str], mentions) -> tuple[list[str], bool]:
    """
    Return the words with a fetch's source said as the place to go, and whether it is brought.

    "pick up the cup from the fridge and ...", "get a soda from the fridge": the place after
    "from" is where to go, whatever the thing fetched is called ("soda" is no typo of "sofa"
    there); "from the sofa to the desk" is two steps; "bring me a cup from the fridge" and "get
    me ..." bring it back: the robot's cell next.
    """
    if not words or words[0] not in FETCH_VERBS or 'from' not in words:
        return words, False
    source = words.index('from')
    # a thing is fetched: "get far away from the fridge" is no fetch
    thing = [w for w in words[1:source] if w not in ('me', 'up', 'out')]
    if not thing or set(thing) & AWAY_WORDS:
        return words, False
    rest = words[source + 1:]
    found = mentions(rest)
    if not found:
        return words, False
    end = found[0].end
    if rest[end:end + 1] == ['to'] and mentions(rest[end + 1:]):  # "from the sofa to the desk"
        rest = [*rest[:end], 'then', 'go', 'to', *rest[end + 1:]]
    return ['go', 'to', *rest], words[1:2] == ['me'] and 'then' not in rest


def placed(words: list[str], mentions, reads=None) -> list[str] | None:
    """
    Return a placing request's words as a go to its place, without the thing placed.

    "put the cup on the table", "place the object under the rock", "set it down below the
    horse": the robot takes the thing there, whatever it is called ("cup" is no typo of
    "up" there), so the place after it is where to go; "in the fridge" and "on the table" are
    the landmark's own place. A placing that says no place ("put the cup down", "leave the
    sofa": the landmark is the thing) is None;
    one whose place `reads` (words -> its Reference) has no Place goes to the network in the
    words it learned one in ("place the object under ..."). Other words stay as they are.
    """
    kept = without_fillers(words)
    opener = phrase_at(kept, 0, REQUEST_OPENERS)  # "could you put ..."
    kept = kept[len(opener.split()):] if opener else kept
    if not kept or kept[0] not in PLACING_VERBS:
        return words

    def opens(k: int) -> bool:
        w, after = kept[k], kept[k + 1:k + 2]
        if kept[k - 1] in ARTICLES:  # "put the left cup on the desk": the thing's own word
            return False
        if w in NUMBERS:
            return bool(after) and (after[0] in UNIT_WORDS or after[0] in DIRECTIONS)
        return w in PLACE_OPENERS

    start = next((k for k in range(1, len(kept)) if opens(k)), None)
    if start is None:
        found = mentions(kept)
        # "put it down", "leave the sofa": no landmark but the thing itself, so no place
        if not found or all(w in ARTICLES for w in kept[1:found[0].start]):
            return None
        return words  # "place the box around the tree": the network reads a place it said
    # "set it down below the horse": the verb's particle, then the place
    if kept[start] in PLACING_PARTICLES and start + 1 < len(kept) and opens(start + 1) and (
        kept[start + 1] not in NUMBERS
    ):
        start += 1
    place = kept[start:]
    if all(w in PLACING_PARTICLES for w in place):  # "put the cup down": no place said
        return None
    found = mentions(place)
    articles = found and all(w in ARTICLES for w in place[1:found[0].start])
    if place[0] in INTO and articles:
        place = ['to', *place[1:]]
    go = ['go', *place]
    # the network learned a placing as PuddleWorld's people said theirs
    return go if reads is None or reads(go).place else ['place', 'the', 'object', *place]


def without_return(words: list[str], mentions) -> tuple[list[str], bool]:
    """
    Return the words without a return said after a place, and whether there was one.

    "go to the fridge and come back", "then return here", "and back": the whole clause after
    the join is the return, and a landmark is named before it. "And come back to the sofa" names
    a place: a step of its own.
    """
    for i, p in sorted(find_phrase(words, JOINS), reverse=True):
        clause = tuple(w for w in words[i + len(p.split()):] if w not in FILLERS)
        if clause in RETURNS and mentions(words[:i]):
            return words[:i], True
    return words, False


def bare(words: list[str], found: list, also=frozenset()) -> bool:
    """Say whether every word besides the landmarks `found` only goes ("go over to the")."""
    named = {k for m in found for k in range(m.start, m.end)}
    return all(
        w in BARE | also
        or w == 'by' and k and words[k - 1] in VISIT_VERBS
        or w in PARTICLES and words[k + 1:k + 2] == ['to']  # "go over to the"
        for k, w in enumerate(words)
        if k not in named
    )


def listed(words: list[str], mentions) -> list[list[str]] | None:
    """
    Return the places of a list of landmarks joined by "and", each its own words, or None.

    "go to the fridge and the couch", "the couch, the fridge and the lamp" (commas are gone
    by now): every word is a landmark's, a go verb, an article or "and". A place said of
    a landmark ("between the fridge and the couch", "one above the star and two left of the
    tree") is not a list.
    """
    found = mentions(words)
    if len(found) < 2 or 'and' not in words or not bare(words, found):
        return None
    places, start = [], 0
    for m in found:
        places.append([w for w in words[start:m.end] if w != 'and'])
        start = m.end
    return places


def choice(words: list[str], mentions) -> bool:
    """
    Say whether the words leave a choice of landmarks open ("the fridge or the couch").

    Two landmarks of different kinds with "or" between them and only going before them;
    what follows ("whichever", "your call") does not matter.
    """
    found = mentions(words)
    for a, b in zip(found, found[1:]):
        gap = words[a.end:b.start]
        if 'or' in gap and set(gap) <= CHOICE_GAP and a.kind != b.kind:
            return bare(words[:a.start], [], {'either'})
    return False


def nearest_of(words: list[str], mentions) -> list[list[str]] | None:
    """
    Return the landmarks of a choice left to nearness, each as going to its nearest, or None.

    "the fridge or the desk, whichever is closer", "the closer of the fridge and the desk",
    "whichever is nearer, the fridge or the sofa": landmarks of different kinds with only
    "and" or "or" between them, and besides going words a choice by nearness: "whichever",
    or "closer of". "The cell closest to the fridge and the desk" is a place, not a choice.
    """
    by_nearness = 'whichever' in words or any(
        w in NEARER and words[k + 1:k + 2] == ['of'] for k, w in enumerate(words)
    )
    if not (by_nearness and set(words) & NEARER):
        return None
    found = mentions(words)
    if len(found) < 2 or len({m.kind for m in found}) < len(found):
        return None
    gaps = {w for a, b in zip(found, found[1:]) for w in words[a.end:b.start]}
    if not (gaps <= CHOICE_GAP | {'and'} and bare(words, found, NEARNESS_CHOICE)):
        return None
    return [['go', 'to', 'the', 'nearest', *words[m.start:m.end]] for m in found]
