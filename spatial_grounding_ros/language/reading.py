# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
One reading of an instruction: what it asks for, and the place it names in the model's words.

`Reader.read` turns what a person says into a `Command`, once per instruction (and cell size),
and everything downstream reads that value: the Grounder's checks, the network's text, the
node and its service. The reading is a list of named stages, each a small function:

1. numbers and lengths: "six feet" -> "4" cells at the map's cell size (units.py, text2num);
2. what the speaker settled on: a self-correction ("the desk, no wait, the fridge") keeps the
   last place said; of several sentences, the one that says where to go or meet;
3. the intent: `stop`, `question`, `negation` and `unsupported` (declined: a goal would say
   something else than was asked), `sequence` (steps in order) or `go`;
4. each step's words: spelling against the relation words (rapidfuzz), landmarks named by the
   table's names and aliases (lexicon.py), paths passed ("down the hall") left out, then the
   model's wording (wording.py) with each landmark held as one slot, so the checks and the
   network read the same words (`Reference.words`);
5. what the words alone rule out: a word where a landmark's name goes that no kind has
   (`unknown-landmark`), a word not understood where it would change the goal (`unreadable`),
   a relation the model never learned (`unsupported`), a side a map has not (`ambiguous`).

Why a table-driven reader and not a parsing library's grammar: what people say to a robot is
not a language to accept or reject. A reading goes on past a word it does not know, keeps
the words it cannot type for the network (which learned from human annotators' free text),
and is cheap (well under a millisecond at ten words). Where the place's grammar (grammar.py)
reads every word, the Reference holds the typed Place (places.py) too.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
import functools

from .checks import (
    ARTICLES, BEFORE_A_NAME, CLAUSES, DIRECTIONS, kindless_pick, MAP_WORDS, moves, NUMBERS,
    opposite_sides, PHRASE_ENDS, QUALIFIERS, relation_reason,
)
from .clauses import (
    beside_negation, choice, condition, fetched, NEAREST_OF, nearest_of, placed, PLACING_VERBS,
    without_action, without_courtesies, without_fillers, without_rejected, without_return,
)
from .grammar import parse
from .lexicon import COMMON_WORDS, Lexicon, Mention
from .phrases import (
    find_phrase, phrase_at, PLURAL_UNITS, sentences, spelling, spelling_targets, texted
)
from .places import Place, PLACE_WORDS, UNIT_WORDS
from .steps import steps as split_steps
from .units import digits, in_cells, LEARNED_COUNT, offsets
from .vocabulary import (
    CORRECTIONS,
    DEICTIC,
    FILLERS,
    GO_VERBS,
    LENGTH_UNITS,
    MOTIONS,
    NEGATIONS,
    PATH_WORDS,
    QUESTION_OPENERS,
    REQUEST_OPENERS,
    SEQUENCE_MARKS,
    SLIPS,
    STOP_HEADS,
    STOP_WORDS,
    UNSUPPORTED,
)
from .wording import (
    canonical,
    cell_before_count,
    cell_for_fixed_target,
    count_first,
    drop_unknown,
    OPENING_VERBS,
    side_of_it,
    tidy,
    unpossessed,
    wording_words,
)
from ..core.text import tokenize

INTENTS = ('go', 'stop', 'question', 'sequence', 'negation', 'unsupported')
SLOT = '@'  # a landmark's slot in a reference's words: '@0', '@1', ... (tokens have no '@')

# the words a path passed ends before: where the place to go is said
PATH_ENDS = (
    frozenset('to toward towards and then until till at by near next beside of from for'.split())
    | frozenset(DIRECTIONS) | frozenset(NUMBERS) | GO_VERBS
)

DIRECTION_ENDS = frozenset('of from the a an to'.split())  # after a direction: "two left of"


def is_slot(word: str) -> bool:
    """Say whether a word is a landmark's slot."""
    return word.startswith(SLOT)


@dataclass(frozen=True)
class Reference:
    """
    One place an instruction names, as the checks and the network read it.

    `words` are the model's wording of the place with each landmark named as one slot
    (`mentions`, in order); `model_words()` gives the network's text for a map's kinds.
    """

    said: str  # the words of the instruction it was read from
    words: tuple[str, ...]  # the model's wording; a mention's slot holds its last word
    mentions: tuple[Mention, ...]  # each spans one word of `words`
    reason: str | None = None  # why the words alone leave no cell to go to
    unknown_words: tuple[str, ...] = ()  # words read as none (left out)
    spelled: tuple[tuple[str, str], ...] = ()  # (word said, word read) for each misspelling
    place: Place | None = None  # the typed place (places.py), when its grammar reads every word

    def model_words(self, names: dict[int, str | None]) -> tuple[list[str], tuple[int, int]]:
        """
        Return the network's words and the offset past its counts.

        `names`: each mentioned kind's name for the network, or None to leave it out (a
        landmark the map lacks). Counts past LEARNED_COUNT are cut to it and the rest is
        returned as (rows, cols) to shift the value map by (units.offsets).
        """
        out = []
        for i, w in enumerate(self.words):
            slot = next((m for m in self.mentions if m.start == i), None)
            if slot is None:
                out.append(w)
            elif names.get(slot.kind) is not None:
                out.append(names[slot.kind])
        cut = offsets(' '.join(out))
        return cut.model_text.split(), cut.extra


# the step of "... and come back": where the robot is when the instruction comes
RETURN_STEP = Reference('back where the robot is now', ('back',), (), place=Place('robot'))


@dataclass(frozen=True)
class Command:
    """What an instruction asks for: an intent and the places it names, in order."""

    text: str
    intent: str  # one of INTENTS
    # go: one (a choice left to nearness, NEAREST_OF: each landmark); sequence: several in
    # order; question: its landmark
    steps: tuple[Reference, ...] = ()
    reason: str | None = None  # negation, unsupported: why no goal is sent
    notes: tuple[str, ...] = field(default=())  # what the reading did ('corrected', ...)

    @property
    def reference(self) -> Reference | None:
        """Return the first place named (the goal's, for go and sequence), or None."""
        return self.steps[0] if self.steps else None


class Reader:
    """
    The reading of instructions for one entity table (its lexicon) and one network.

    `known`: every word the network learned (its vocabulary); `model_names`: the network's
    own landmark names, which are landmarks only on its own table (`own_table`).
    """

    def __init__(self, lexicon: Lexicon, known=frozenset(), model_names=(), own_table=True):
        self.lexicon = lexicon
        table_words = {w for p in lexicon.phrases for w in p}
        self.classes = (
            frozenset(DIRECTIONS) | frozenset(NUMBERS) | QUALIFIERS | CLAUSES | MAP_WORDS
            | COMMON_WORDS | wording_words() | STOP_WORDS | GO_VERBS | FILLERS | DEICTIC
            | PATH_WORDS | frozenset(LENGTH_UNITS) | frozenset(OPENING_VERBS) | PLACE_WORDS
            | PLACING_VERBS | {w for p in (*NEGATIONS, *CORRECTIONS, *SEQUENCE_MARKS,
                                           *UNSUPPORTED, *QUESTION_OPENERS, *REQUEST_OPENERS)
                               for w in tokenize(p)}
        )  # fmt: skip
        names = {w for n in model_names for w in tokenize(n.replace('_', ' '))}
        # a word that says what a landmark is: on another table, the network's own names
        # ("circle", "tree") and its other nouns name no kind of the user's
        self.slot_known = self.classes | table_words | (frozenset(known) if own_table else set())
        self.slot_known -= set() if own_table else names
        self.vocab = frozenset(known)
        self.known = self.classes | table_words | self.vocab
        self.read = functools.lru_cache(maxsize=256)(self._read)

    # -- stage 1 and 2: the text the speaker settled on ---------------------------------
    def _read(self, text: str, cell_size: float | None = None) -> Command:
        """Return the Command of an instruction (cached: a node reads one on every map)."""
        said = count_first(in_cells(digits(unpossessed(text)), cell_size))
        parts = [texted([SLIPS.get(w, w) for w in tokenize(s)]) for s in sentences(said)]
        words = [w for part in parts for w in part]
        if not words:
            raise ValueError('instruction has no words')
        notes = []
        # a question opens as one, or ends in "?" asking no one to go anywhere ("can you go
        # to the fridge?" and "let's go right of the spade, cool?" are requests)
        question = self.asks(parts[-1]) or (
            text.rstrip().endswith('?') and not set(words) & (GO_VERBS | PLACING_VERBS)
        )
        words = without_rejected(words, self.lexicon.mentions)  # "instead of the fridge"
        fixed = self.corrected(words)
        if fixed is not None:
            words = fixed
            notes.append('corrected')
        elif len(parts) > 1 and not question:
            chosen = self.meeting_sentence(parts)
            if chosen is not None:
                words = chosen
                notes.append('sentence')
        return self.intent(text, words, question, cell_size, tuple(notes))

    def corrected(self, words: list[str]) -> list[str] | None:
        """
        Return the words after the speaker's last correction, or None if there is none.

        "the desk, no wait, the fridge": the fridge; "left of the sofa, sorry, I mean right of
        it": "it" is the place said before the correction.
        """
        found = []
        for i, p in find_phrase(words, CORRECTIONS):
            after = words[i + len(p.split()):]
            if p == 'no' and (i == 0 or not after):
                continue  # "no, ..." opening a request, or a trailing "no"
            counted = any(w in NUMBERS for w in words[:i])
            if self.lexicon.mentions(after) or set(after) & {'it', 'its'} or (
                counted and after and all(w in NUMBERS or w in UNIT_WORDS for w in after)
            ):
                found.append((i, p))
        if not found:
            return None
        i, p = found[-1]
        before, after = words[:i], words[i + len(p.split()):]
        counts = [k for k, w in enumerate(before) if w in NUMBERS]
        if counts and after and all(w in NUMBERS or w in UNIT_WORDS for w in after):
            # "three cells below the fridge, sorry, two": the count said again
            return [*before[:counts[-1]], after[0], *before[counts[-1] + 1:]]
        if counts and after and after[0] in DIRECTIONS:
            # "one cell right of the circle, no, left of it": the count said before stays
            after = before[counts[-1]:counts[-1] + 1] + after
        earlier = self.lexicon.mentions(before)
        if not self.lexicon.mentions(after) and earlier:
            landmark = ['the', *earlier[-1].words]
            after = [
                x for w in after
                for x in (landmark if w == 'it' else ['of', *landmark] if w == 'its' else [w])
            ]  # fmt: skip
        if after and after[0] not in GO_VERBS:
            after = [w for w in before if w in GO_VERBS][:1] + after
        return after

    def meeting_sentence(self, parts: list[list[str]]) -> list[str] | None:
        """
        Return the description from the sentence that says where to go or meet, or None.

        What comes before it is context ("I'm in the kitchen. Meet me at the fridge."); what
        comes after may say more of the place ("It is across from the sofa", "the cell is two
        left of the star"), and is kept, but only the place's own sentence can name an
        unknown landmark.
        """
        said = [k for k, p in enumerate(parts) if not self.negated(p)]
        going = [k for k in said if set(parts[k]) & GO_VERBS]
        named = [k for k in said if self.lexicon.mentions(parts[k])]
        start = (going or named or [None])[0]
        if not start:  # the first sentence, or none: the words as they are
            return None
        return [w for p in parts[start:] for w in p]

    # -- stage 3: the intent -----------------------------------------------------------
    def asks(self, words: list[str]) -> bool:
        """Say whether the words open as a question rather than a polite request."""
        kept = [w for w in words if w not in FILLERS]
        opener = phrase_at(kept, 0, REQUEST_OPENERS)
        if opener is not None:
            n = len(opener.split())
            return not set(kept[n:n + 2]) & (GO_VERBS | PLACING_VERBS)
        return phrase_at(kept, 0, QUESTION_OPENERS) is not None

    def negated(self, words: list[str]) -> str | None:
        """Return the negation of the request in the words ("don't", "avoid"), or None."""
        for i, p in find_phrase(words, NEGATIONS):
            rest = words[i + len(p.split()):]
            if p in ("don't", 'dont', 'do not', 'never') and rest[:1] == ['mind']:
                continue
            return p
        return None

    def intent(self, text, words, question, cell_size, notes) -> Command:
        words = without_courtesies(words)  # "if you can": asks nothing (clauses.py)
        mentions = self.lexicon.mentions(words)
        content = [w for w in words if w not in FILLERS]
        if not mentions and content and all(w in STOP_WORDS for w in content) and (
            set(content) & STOP_HEADS
        ):
            return Command(text, 'stop', notes=notes)
        negation = self.negated(words)
        if question:  # of a landmark the table has, or of one it lacks ("where is the piano?")
            ref = self.reference(words, cell_size)
            asked = mentions or (ref.reason or '').startswith('unknown-landmark')
            return Command(text, 'question', (ref,) if asked else (), notes=notes)
        if negation is not None:  # "don't go to the fridge, go to the sofa": the sofa
            kept = beside_negation(words, negation, self.lexicon.mentions)
            if kept is None:
                why = f'negation: "{negation}" says where not to go'
                return Command(text, 'negation', (), why, notes)
            words, mentions, notes = kept, self.lexicon.mentions(kept), (*notes, 'negation')
        words, brought = fetched(words, self.lexicon.mentions)  # "get a soda from the fridge"
        if not mentions and placed(words, self.lexicon.mentions) is None:  # "put it down"
            return Command(text, 'unsupported', (), f'unsupported: "{text}" says no place', notes)
        words, back = without_return(words, self.lexicon.mentions)  # "and come back"
        words, action = without_action(words, self.lexicon.mentions)  # "and sit down"
        notes += ('action',) if action else ()
        content = [w for w in words if w not in FILLERS]
        said_if = condition(content)
        if said_if is not None:
            return Command(text, 'unsupported', (), f'unsupported: "{said_if}" is a condition '
                           'the robot cannot check', notes)
        motion = find_phrase(content[:2], MOTIONS)
        rest = set(content[2:])
        if motion and not rest & (GO_VERBS | set(DIRECTIONS) | set(NUMBERS) | QUALIFIERS):
            # "follow the wall", "turn towards the door": a motion, not a place
            return Command(text, 'unsupported', (),
                           f'unsupported: "{motion[0][1]}" asks for a motion, not a place', notes)
        if not mentions:  # a placing's thing is no landmark: its place may name one
            unknown = self.reference(placed(words, self.lexicon.mentions) or words, cell_size)
            if unknown.reason is not None and unknown.reason.startswith('unknown-landmark'):
                return Command(text, 'go', (unknown,), None, notes)
            found = find_phrase(content, UNSUPPORTED)
            deictic = set(content) & DEICTIC
            if unknown.unknown_words and not found:
                words_said = ', '.join(f'"{w}"' for w in unknown.unknown_words)
                return Command(text, 'go', (replace(unknown, reason=f'unreadable: {words_said}'),),
                               None, notes)
            if moves(content):
                what = ' '.join(content[:5])
                return Command(text, 'unsupported', (), f'unsupported: "{what}" is a move from '
                               'where the robot is, not a place on the map', notes)
            if found or deictic or not set(content) & (set(DIRECTIONS) | QUALIFIERS):
                what = found[0][1] if found else ' '.join(content[:4])
                return Command(text, 'unsupported', (), f'unsupported: "{what}" names no '
                               'landmark or cell on the map', notes)
        options = nearest_of(words, self.lexicon.mentions)  # "..., whichever is closer"
        if options:  # each a step; the grounder takes the one nearest the robot
            steps = tuple(self.reference(o, cell_size) for o in options)
            return Command(text, 'go', steps, None, (*notes, NEAREST_OF))
        if choice(words, self.lexicon.mentions):  # "the fridge or the couch"
            ref = self.reference(words, cell_size)
            return Command(text, 'go', (replace(ref, reason='ambiguous: one place or another '
                                        'is named: say which'),), None, notes)
        # "put the cup on the desk": a go to the place it reads ("... and put it on the desk")
        reads = functools.partial(self.reference, cell_size=cell_size)
        steps = [placed(s, self.lexicon.mentions, reads)
                 for s in split_steps(words, self.lexicon.mentions)]
        if None in steps:  # "leave the sofa", "put the chair down": a placing, no place said
            return Command(text, 'unsupported', (), f'unsupported: "{text}" says no place', notes)
        back = (RETURN_STEP,) * (back or brought)
        refs = tuple(self.reference(s, cell_size) for s in steps) + back
        return Command(text, 'sequence' if len(refs) > 1 else 'go', refs, None, notes)

    def reference(self, words: list[str], cell_size: float | None) -> Reference:
        """Return one step's Reference: its spelling read, its slots, its reading's reason."""
        said = ' '.join(words)
        kept = [w for w in words if w not in FILLERS]
        opener = phrase_at(kept, 0, REQUEST_OPENERS)  # "could you head over to": a request
        if opener is not None:
            words = kept[len(opener.split()):] or words
        words, spelled = self.spelled(words)
        words = self.without_paths(words)
        mentions = self.lexicon.mentions(words)
        unknown = [
            (i, w) for i, w in enumerate(words)
            if w not in self.known and not any(m.start <= i < m.end for m in mentions)
            and not w.isdigit()
        ]  # fmt: skip
        slotted, slots = slot(words, mentions)
        slotted = without_fillers(slotted) or slotted
        named = {f'{SLOT}{k}': self.lexicon.table.names[m.kind] for k, m in enumerate(slots)}
        place = None if unknown else parse(slotted, named)  # the typed place (places.py)
        reason = self.reason_of(words, mentions, unknown, place)
        canon = canonical(slotted, [i for i, w in enumerate(slotted) if is_slot(w)])
        # the words the network learned and the slots: an unknown word cannot move the goal
        slots_and_counts = {w for w in canon if is_slot(w) or w.isdigit()}
        kept = tidy(drop_unknown(canon, self.vocab | slots_and_counts))
        sided = side_of_it(kept, [i for i, w in enumerate(kept) if is_slot(w)])
        if place is None and not unknown and sided != kept:  # "the star and one to its left"
            place = parse(sided, named)
        kept = cell_for_fixed_target(sided, [i for i, w in enumerate(sided) if is_slot(w)])
        kept = cell_before_count(kept)
        return unslot(
            said, kept, slots, reason, tuple(w for _, w in unknown), tuple(spelled), place
        )

    def spelled(self, words: list[str]) -> tuple[list[str], list[tuple[str, str]]]:
        """Return the words with each misspelt relation word read as the word meant."""
        mentions = self.lexicon.mentions(words)
        out, spelled = [], []
        for i, w in enumerate(words):
            if w in self.known or w.isdigit() or any(m.start <= i < m.end for m in mentions):
                out.append(w)
                continue
            meant = spelling(w, spelling_targets(words, i))
            if meant is not None:
                spelled.append((w, meant))
            out.append(meant or w)
        return out, spelled

    def without_paths(self, words: list[str]) -> list[str]:
        """Return the words without a path passed ("down the hall", "across the room")."""
        named = {i for m in self.lexicon.mentions(words) for i in range(m.start, m.end)}
        out, i = [], 0
        while i < len(words):
            if words[i] in PATH_WORDS and words[i + 1:i + 2] and words[i + 1] in ARTICLES:
                j = i + 2
                while j < len(words) and j not in named and words[j] not in PATH_ENDS:
                    j += 1
                # a path ends before the place: "down the hall to the fridge"; "down the side
                # of the sofa" or "up the fridge" are no path
                if j > i + 2 and j < len(words) and j not in named and words[j] != 'of':
                    i = j + (words[j] == 'and')
                    continue
            out.append(words[i])
            i += 1
        return out

    def reason_of(self, words, mentions, unknown, place=None) -> str | None:
        """Return why the words alone leave no cell to go to, or None."""
        why = relation_reason(words, place is not None) or opposite_sides(words, mentions)
        if mentions and why:
            return why
        picked = kindless_pick(words)  # "the leftmost object"
        if picked:
            return picked
        first = mentions[0].start if mentions else len(words)
        for i, w in unknown:
            nxt = words[i + 1] if i + 1 < len(words) else None
            prev = words[i - 1] if i else None
            if w in self.slot_known:
                continue
            # the referent's slot: a word that ends its phrase after an article or a relation
            # ("below the piano", "go to the box"), before any landmark of the table
            ends = nxt is None or nxt in CLAUSES | PHRASE_ENDS
            before = BEFORE_A_NAME if not mentions else ARTICLES
            if i < first and ends and prev in before:
                return f'unknown-landmark: {w}'
            # a word not understood where a direction goes: after a count (and its unit),
            # before the landmark ("two cells xqzv of the sofa", "one undr the sofa")
            counted = prev in NUMBERS or (
                prev in UNIT_WORDS and i > 1 and words[i - 2] in NUMBERS
            )
            if counted and (nxt in DIRECTION_ENDS or any(m.start == i + 1 for m in mentions)):
                return f'unreadable: "{w}"'
            if nxt in PLURAL_UNITS and i < first:  # a count's place: "go xqz cells left of"
                return f'unreadable: "{w}"'
        if not mentions:
            for i, w in enumerate(words):
                if w in self.slot_known or w in self.classes:
                    continue
                prev = words[i - 1] if i else None
                nxt = words[i + 1] if i + 1 < len(words) else None
                if prev in BEFORE_A_NAME and (nxt is None or nxt in CLAUSES | PHRASE_ENDS):
                    return f'unknown-landmark: {w}'
        return None


def slot(words: list[str], mentions: list[Mention]) -> tuple[list[str], list[Mention]]:
    """Return the words with each mention as one slot word ('@k'), and the mentions."""
    out, slots, i = [], [], 0
    starts = {m.start: m for m in mentions}
    while i < len(words):
        if i in starts:
            out.append(f'{SLOT}{len(slots)}')
            slots.append(starts[i])
            i = starts[i].end
        else:
            out.append(words[i])
            i += 1
    return out, slots


def unslot(said, words, slots, reason, unknown, spelled, place=None) -> Reference:
    """Return the Reference of slotted words: each slot the mention's last word."""
    out, mentions = [], []
    for w in words:
        if is_slot(w):
            m = slots[int(w[1:])]
            mentions.append(replace(m, start=len(out), end=len(out) + 1))
            out.append(m.words[-1])
        else:
            out.append(w)
    return Reference(said, tuple(out), tuple(mentions), reason, unknown, spelled, place)


__all__ = ['Command', 'INTENTS', 'LEARNED_COUNT', 'Reader', 'Reference']
