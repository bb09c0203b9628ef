"""
A plain Python API over a trained model, for users who do not want topics.

    g = Grounder.from_checkpoint()                    # the packaged pw_t-rnet-attn
    result = g.ground(grid, "reach cell two below the westernmost rock")
    result.goal, result.confidence, result.reason, result.values, result.alternatives

    kitchen = Grounder.from_checkpoint(entities='kitchen.yaml')  # a table of your own

A grid may use any entity table: the landmarks an instruction names (by name, alias, plural
or a one-letter typo) are grounded as the model's own kinds (language/lexicon.py). When the
table and the map show that no cell fits (a landmark that is not there, a name no kind has,
a cell past the edge, several landmarks named as one, an obstacle), or the model is unsure,
the grounding declines: `goal` is None and `reason` says why (language/checks.py).

The ROS grounder node is a thin adapter over this class.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import replace
import functools
from pathlib import Path

import numpy as np
import torch

from .core.confidence import certainty, judged, mass_around, probability
from .core.entities import EntityTable, PUDDLEWORLD_NONUNIQUE, PUDDLEWORLD_UNIQUE
from .core.footprints import nearest_cell, reduce_footprints
from .core.grounding import Grounding, nearest_option, REASONS  # noqa: F401 (REASONS: API)
from .core.text import tokenize
from .data.augment import MIRROR_IMAGES, mirror_instruction
from .language import compose
from .language.approach import approach_for
from .language.checks import map_reason, named_sides, place_offsets, said
from .language.clauses import NEAREST_OF
from .language.compose import plain_row_col, renamed, shifted
from .language.lexicon import Lexicon, Mention, Translation
from .language.places import composed, learned, Place, surface
from .language.reading import Command, Reader, Reference
from .models.checkpoints import load_checkpoint, Loaded
from .models.protocol import TextCode

DEFAULT_CHECKPOINT = 'pw_t-rnet-attn'
# the map as it is, then its mirror images (the map axes each flips), as training mirrors its
# human examples (data/augment.py)
IMAGES = ((), *MIRROR_IMAGES)
# maps of up to this many cells (64x64) may be grounded with their mirror images too: on a
# larger map few groundings are that sure of one cell, and four images are four times the work
MIRROR_AVERAGE_CELLS = 64 * 64
# ... when the map alone leaves the network less sure than this of its best cell (calibrated):
# the images' mean is steadier where it is unsure, and only there (docs/benchmarks.md has
# what it costs and what it earns)
MIRROR_AVERAGE_BELOW = 0.95


# the least calibrated confidence a goal is sent with (docs/honest-answers.md has the
# trade-off): under it a grounding declines, low-confidence
DEFAULT_MIN_CONFIDENCE = 0.1
CACHED_INSTRUCTIONS = 64  # whose text codes are kept: a node grounds one on new maps


def resolve_table(entities: str | Path | EntityTable | None) -> EntityTable | None:
    """Return an entity table given as a table, a YAML path or None."""
    if entities is None or isinstance(entities, EntityTable):
        return entities
    return EntityTable.from_yaml(entities)


def imaged(grid: np.ndarray, images) -> torch.Tensor:
    """Return the map's `images` (each the axes it flips) as one batch (I, H, W)."""
    if images == IMAGES[:1]:  # the map as it is
        return torch.as_tensor(grid, dtype=torch.int64)[None]
    return torch.as_tensor(np.stack([np.flip(grid, axes) for axes in images]))


def averaged(values: np.ndarray, images) -> np.ndarray:
    """Return the mean of the images' value maps (I, H, W), each flipped back."""
    return np.mean([np.flip(v, axes) for v, axes in zip(values, images)], 0)


class Grounder:
    def __init__(
        self,
        loaded: Loaded,
        entities: EntityTable | None = None,
        min_confidence: float = DEFAULT_MIN_CONFIDENCE,
        cached_instructions: int = CACHED_INSTRUCTIONS,
        cell_size: float | None = None,
        kinds_by: str = 'name',
        mirror_average_cells: int = MIRROR_AVERAGE_CELLS,
        mirror_average_below: float = MIRROR_AVERAGE_BELOW,
    ):
        """
        Wrap a loaded checkpoint, for maps in `entities` (default: the checkpoint's table).

        A model trained on PuddleWorld reads any table (language/lexicon.Translation); others
        only their own. `min_confidence` (0..1): a grounding less sure than this declines.
        `cell_size`: metres per cell, for distances in metres (language/units.py); a table's
        landmarks may cover several cells (EntityTable.has_footprints, core/footprints.py).
        `kinds_by`: how the model's own landmark names take its kinds (lexicon.KINDS_BY).
        `mirror_average_cells`, `mirror_average_below`: on maps of at most this many cells, a
        value map whose best cell has a calibrated chance below `mirror_average_below` is
        replaced by the mean of the model's over the map and its three mirror images, each
        read with its direction words swapped (IMAGES; the three in one batch): where the
        model is unsure of a cell, its mirror images seldom are unsure the same way
        (`mirror_average_cells` 0: never; `mirror_average_below` 1: every map up to that
        size). The text codes of the last
        `cached_instructions` instructions are kept (t-RNetAttn: the relation table over all
        kinds), since a node grounds the same instruction on new maps.
        """
        if not 0 <= min_confidence <= 1:
            raise ValueError(f'min_confidence must be in 0..1, got {min_confidence}')
        self.loaded, self.cached_instructions = loaded, cached_instructions
        self.model, self.vocab = loaded.model, loaded.vocab
        self.model_entities = loaded.entities
        self.entities = entities if entities is not None else loaded.entities
        self.min_confidence, self.cell_size = min_confidence, cell_size
        if not 0 <= mirror_average_below <= 1:
            raise ValueError(f'mirror_average_below must be in 0..1, got {mirror_average_below}')
        self.mirror_average_cells = mirror_average_cells
        self.mirror_average_below = mirror_average_below
        self.mirror_averaged = 0  # value maps averaged over the mirror images so far
        self.translation = None
        if loaded.entities.domain == 'puddleworld':
            self.translation = Translation(
                self.entities,
                loaded.entities,
                PUDDLEWORLD_UNIQUE,
                PUDDLEWORLD_NONUNIQUE,
                kinds_by,
            )
        elif self.entities.names != loaded.entities.names:
            raise ValueError(
                f'a model trained on the {loaded.entities.domain} table reads only that table; '
                f'the {self.entities.domain} table needs a PuddleWorld model'
            )
        self.lexicon = self.translation.lexicon if self.translation else Lexicon(self.entities)
        self.reader = Reader(
            self.lexicon,
            self.vocab.words[2:],
            loaded.entities.names,
            own_table=self.entities.names == loaded.entities.names,
        )
        # calibration: confidence is the softmax of the values at this temperature
        self.temperature = float(loaded.header.get('calibration', {}).get('temperature', 1.0))
        self.model.eval()
        # instruction -> (its words for the model, {images: text code}); least recently used
        # first
        self.text_codes: OrderedDict[str, tuple[str, dict]] = OrderedDict()
        # an instruction is checked once, not on every map (a failed check is not kept)
        self.check_instruction = functools.lru_cache(maxsize=256)(self.check_instruction)

    @classmethod
    def from_checkpoint(
        cls,
        checkpoint: str | Path = DEFAULT_CHECKPOINT,
        entities: str | Path | EntityTable | None = None,
        min_confidence: float = DEFAULT_MIN_CONFIDENCE,
        cell_size: float | None = None,
        mirror_average_cells: int = MIRROR_AVERAGE_CELLS,
        mirror_average_below: float = MIRROR_AVERAGE_BELOW,
    ) -> 'Grounder':
        """Load a packaged checkpoint by name or a path, for maps of any entity table."""
        return cls(
            load_checkpoint(checkpoint),
            resolve_table(entities),
            min_confidence,
            cell_size=cell_size,
            mirror_average_cells=mirror_average_cells,
            mirror_average_below=mirror_average_below,
        )

    def check(self, grid: np.ndarray, instruction: str) -> None:
        """Raise ValueError naming what is wrong with an input."""
        self.check_grid(grid)
        self.check_instruction(instruction)

    def check_grid(self, grid: np.ndarray) -> None:
        """Run the grid half of check(): the ROS node checks a map when it arrives."""
        grid = np.asarray(grid)
        if grid.ndim != 2 or 0 in grid.shape:
            raise ValueError(f'grid must be a non-empty 2-D array, got shape {grid.shape}')
        # entity indices: a fraction (or NaN) names no entity, and int64 would truncate it to one
        if grid.dtype.kind not in 'iu':
            if grid.dtype.kind == 'f':
                not_whole = grid[~(np.isfinite(grid) & (grid == np.round(grid)))]
            else:  # bool, complex, strings, objects: not entity indices even when they look it
                not_whole = grid.reshape(-1)
            if not_whole.size:
                raise ValueError(
                    f'grid must hold integer entity indices, got {grid.dtype} values such as '
                    f'{not_whole[0].item()!r}'
                )
        if grid.min() < 0 or grid.max() >= len(self.entities):
            bad = np.unique(grid[(grid < 0) | (grid >= len(self.entities))])
            raise ValueError(
                f'grid holds entity values {bad.tolist()[:10]} outside the '
                f'{self.entities.domain} table (0..{len(self.entities) - 1})'
            )

    def check_instruction(self, instruction: str) -> None:
        """Run the instruction half of check(): the node checks one before any map arrives."""
        words = tokenize(instruction)
        if not words:
            raise ValueError('instruction has no words')
        if not self.lexicon.mentions(words) and not any(w in self.reader.known for w in words):
            raise ValueError(f'no word of the instruction {instruction!r} is in the vocabulary')

    def read(self, instruction: str, cell_size: float | None = None) -> Command:
        """Return the one reading of an instruction that every stage reads (cached)."""
        return self.reader.read(instruction, self.cell_size if cell_size is None else cell_size)

    @torch.inference_mode()
    def text_code(self, model_text: str, images: tuple = IMAGES[:1]) -> TextCode:
        """
        Return the network's text code of its words for `images` of the map.

        The code holds the words as said of each of `images` (some of IMAGES: the first is
        the words as they are). Each is computed once, when a map first needs it, while the
        words are in use.
        """
        codes = self.text_codes.pop(model_text, None)
        if codes is None:
            codes = {}
            if len(self.text_codes) >= self.cached_instructions:
                self.text_codes.popitem(last=False)
        self.text_codes[model_text] = codes
        if images not in codes:
            # a mirror image's wording swaps words one for one (augment.SWAP_TABLES), so every
            # image's tokens are as long as the words' and carry no padding, whichever images
            # are encoded together
            said = [mirror_instruction(model_text, axes) for axes in images]
            codes[images] = self.model.text_code(torch.as_tensor(self.vocab.encode_batch(said)))
        return codes[images]

    # inference mode: no autograd bookkeeping on any tensor, a tenth of a 10x10 map's time
    @torch.inference_mode()
    def ground(
        self,
        grid: np.ndarray,
        instruction: str,
        cell_size: float | None = None,
        robot_cell: tuple[int, int] | None = None,
    ) -> Grounding:
        """
        Ground an instruction on a grid of this grounder's table.

        The stages: check the map, read the instruction (one Command, language/reading.py),
        then by its intent ground each place it names (`ground_reference`), answer a
        question, or say why no goal is sent. `cell_size` (metres per cell; default: the
        grounder's) turns lengths into cells; a length without one raises ValueError.
        `robot_cell`: the robot's (row, col), if known: a goal beside a solid landmark is then
        the one it reaches first (language/approach.py).
        """
        self.check(grid, instruction)
        size = self.cell_size if cell_size is None else cell_size
        command = self.read(instruction, size)
        grid = np.asarray(grid, dtype=np.int64)
        if command.intent in ('go', 'sequence'):
            steps = [self.ground_reference(grid, instruction, ref, robot_cell, size)
                     for ref in command.steps]
            return self.in_order(instruction, command, steps, robot_cell)
        if command.intent == 'question':
            return self.answered(grid, instruction, command)
        return self.no_goal(grid, instruction, command, command.reason)

    def ground_reference(
        self, grid: np.ndarray, instruction: str, ref: Reference, robot_cell=None, cell_size=None
    ) -> Grounding:
        """Return the grounding of one place: the network's value map, judged and checked."""
        if ref.place is not None and (
            composed(ref.place) or plain_row_col(ref.place, self.entities, grid, ref.mentions)
        ):
            return self.ground_composed(grid, instruction, ref, robot_cell, cell_size)
        model_grid, names, mentions = self.model_view(grid, ref)
        words, extra = self.network_words(ref, names, ref.place)
        values, aux = self.network(model_grid, words)
        values = shifted(values, extra)
        best, confidence, alternatives = self.judge(values)
        offsets = self.offsets(ref)
        reason = ref.reason or map_reason(self.entities, grid, list(ref.words), mentions, offsets)
        # the approach step: sent to a solid landmark, the robot stops beside it
        goal, referent = best, nearest_cell(grid, [m.kind for m in mentions], best)
        approach = approach_for(
            self.entities, grid, list(ref.words), mentions, best, robot_cell, offsets
        )
        if approach is not None:
            goal, referent, reason = approach.goal, approach.referent, reason or approach.reason
            t = self.temperature
            alternatives = [(cell, probability(values, cell, t)) for cell in approach.others]
            # the robot stops beside the landmark, whichever side the network favoured: the
            # chance that it is the place meant is the mass on the landmark and around it
            confidence = mass_around(values, grid, referent, self.temperature)
        beside = approach is not None and approach.goal is not None
        return self.grounding(grid, instruction, ref, values, aux, words, goal, best, confidence,
                              reason, alternatives, referent, beside)

    def grounding(self, grid, instruction, ref, values, aux, words, goal, best, confidence,
                  reason, alternatives, referent, beside) -> Grounding:
        """Return a Grounding of one place, judged: on an obstacle, or too unsure, declined."""
        if reason is None and goal is not None and int(grid[goal]) in self.entities.never_goal:
            reason = 'goal-on-obstacle'
        if reason is None and confidence < self.min_confidence:
            reason = f'low-confidence: {confidence:.2f} < {self.min_confidence:.2f}'
        attention = None if aux is None else aux['attention']
        relation = np.zeros_like(values) if aux is None else aux['relation_map'][0].numpy()
        return Grounding(
            instruction, values, relation, None if reason else goal, words,
            None if attention is None else attention[0].tolist(), list(ref.unknown_words),
            best=best,
            confidence=confidence,
            reason=reason,
            alternatives=alternatives,
            landmarks=self.named(list(ref.mentions)),
            referent=referent,
            model_instruction=' '.join(words),
            beside=beside,
        )

    def network_words(self, ref: Reference, names: dict, place: Place | None):
        """
        Return the network's words for a place and the offset to shift its value map by.

        A place the grammar read is said to the network in the words it learned it from
        (places.surface, style 0, the landmarks in its own names); the part of an offset past
        what it learned shifts its value map (places.learned). Words the grammar does not
        read go to the network as read (Reference.model_words).
        """
        table_names = {self.entities.names[k]: v for k, v in names.items()}
        if place is None or None in table_names.values():
            return ref.model_words(names)
        # an object named on the goal cell ("reach rock between ...") says no more than "cell"
        # of a place its relation fixes (wording.cell_for_fixed_target)
        place, rest = learned(replace(place, on=None))
        return surface(renamed(place, table_names)).split(), rest

    def network(self, model_grid: np.ndarray, words: list[str]):
        """
        Return the network's value map for its words, and its aux of the map itself.

        Where it is unsure of its best cell on a map it may average (mirror_average_cells,
        mirror_average_below), the mean over the map and its mirror images.
        """
        text = ' '.join(words)
        values, aux = self.model.ground(imaged(model_grid, IMAGES[:1]), self.text_code(text), True)
        values = values.numpy()
        if model_grid.size <= self.mirror_average_cells and (
            self.mirror_average_below >= 1
            or certainty(values[0], self.temperature) < self.mirror_average_below
        ):
            mirrors = self.model.ground(
                imaged(model_grid, IMAGES[1:]), self.text_code(text, IMAGES[1:])
            )
            self.mirror_averaged += 1
            return averaged(np.concatenate([values, mirrors.numpy()]), IMAGES), aux
        return values[0], aux

    def ground_composed(
        self, grid: np.ndarray, instruction: str, ref: Reference, robot_cell=None, cell_size=None
    ) -> Grounding:
        """Return the grounding of a place composed from the network's groundings of its parts."""
        model_grid, names, _ = self.model_view(grid, ref)

        def network(place: Place):
            words, rest = self.network_words(ref, names, place)
            return (*self.network(model_grid, words), words, rest)

        kinds = {self.entities.names[m.kind]: m.kind for m in ref.mentions}
        c = compose.compose(ref.place, self.entities, grid, kinds, ref.reason, network,
                            self.judge, robot_cell, cell_size)
        if c.values is not None:  # a shift of the network's value map
            best, confidence, alternatives = self.judge(c.values)
            referent = nearest_cell(grid, [m.kind for m in ref.mentions], best)
            return self.grounding(
                grid, instruction, ref, c.values, c.aux, c.words, best, best, confidence,
                c.reason, alternatives, referent, False,
            )
        return self.placed(grid, instruction, ref, c.cells, c.confidence, c.reason, c.words,
                           c.landmark_cell, robot_cell)

    def placed(
        self, grid, instruction, ref, cells, confidence, reason, words, landmark_cell, robot_cell
    ) -> Grounding:
        """
        Return the grounding of a composed place's cells ([(cell, share)]: its value map).

        `landmark_cell`: the place is this landmark's own cell; a solid one is approached.
        """
        values = compose.cell_values(cells, grid.shape)
        # the first of equal shares; its chance: the network's for the landmarks, times its share
        (best, share), *others = sorted(cells, key=lambda c: -c[1]) or [((0, 0), 0.0)]
        p_best = confidence * share
        alternatives = [(cell, confidence * s) for cell, s in others]
        goal, referent, beside = best, None, False
        if landmark_cell is not None:
            referent = landmark_cell
            kind = int(grid[landmark_cell])
            approach = approach_for(
                self.entities, grid, [self.entities.names[kind]],
                [Mention(kind, 0, 1, (self.entities.names[kind],))], landmark_cell, robot_cell,
            )
            if approach is not None:
                goal, referent = approach.goal, approach.referent
                reason, beside = reason or approach.reason, approach.goal is not None
        elif ref.mentions and cells:
            referent = nearest_cell(grid, [m.kind for m in ref.mentions], goal)
        return self.grounding(
            grid, instruction, ref, values, None, words, None if reason else goal, best,
            p_best if cells else 0.0, reason, alternatives, referent, beside,
        )

    def offsets(self, ref: Reference) -> list | None:
        """Return each landmark's offset as the typed place says it, or None: the words say."""
        if ref.place is None:
            return None
        return place_offsets(ref.place, list(ref.mentions), self.entities.names)

    def model_view(self, grid: np.ndarray, ref: Reference):
        """
        Return the map in the network's kinds, each mentioned kind's name for it, and mentions.

        A model of PuddleWorld reads any table (language/lexicon.Translation): the landmarks
        named become its kinds (a landmark the map lacks has no name: it is left out), and a
        landmark over several cells is reduced to its anchor on the side its offset leaves it.
        """
        mentions = list(ref.mentions)
        if self.translation is None:
            return grid, {m.kind: self.entities.names[m.kind] for m in mentions}, mentions
        translated = self.translation.translate(grid, list(ref.words), mentions)
        model_grid = translated.grid
        names = {k: self.model_entities.names[v] for k, v in translated.kinds.items()}
        for m in mentions:
            if m.kind in self.entities.obstacles:
                names[m.kind] = self.model_entities.names[self.model_entities.obstacles[0]]
        if self.entities.has_footprints:
            sides = named_sides(list(ref.words), mentions, self.offsets(ref))
            sides = {translated.kinds[k]: v for k, v in sides.items() if k in translated.kinds}
            model_grid = reduce_footprints(model_grid, sides, self.model_entities.obstacles[0])
        return model_grid, names, mentions

    def in_order(self, instruction, command: Command, steps: list[Grounding], robot_cell=None):
        """Return a go's grounding (of a choice: the nearest), or a sequence's, with each step."""
        first = steps[0]
        if command.intent == 'go':
            return nearest_option(steps, robot_cell) if NEAREST_OF in command.notes else first
        declined = next(((k, g) for k, g in enumerate(steps) if g.goal is None), None)
        reason = None if declined is None else f'{declined[1].reason} (step {declined[0] + 1})'
        return replace(
            first,
            instruction=instruction,
            goal=None if reason else first.goal,
            reason=reason,
            intent='sequence',
            steps=steps,
            confidence=float(np.prod([g.confidence for g in steps])),
            landmarks=list(dict.fromkeys(n for g in steps for n in g.landmarks)),
        )

    def answered(self, grid: np.ndarray, instruction: str, command: Command) -> Grounding:
        """Return a question's grounding: no goal; the landmark asked of, in words and cell."""
        ref = command.reference
        out = self.no_goal(grid, instruction, command, None)
        if ref is None or not ref.mentions:  # none named, or one the table lacks (its reason)
            code, _, word = ((ref and ref.reason) or '').partition(': ')
            unknown = code == 'unknown-landmark' and f'no landmark I know of is called "{word}"'
            return replace(out, answer=unknown or 'I cannot tell which landmark is asked of')
        kind = ref.mentions[0].kind
        name = said(self.entities, kind)
        cells = np.argwhere(grid == kind)
        if not len(cells):
            return replace(out, answer=f'there is no {name} on the map', landmarks=[name])
        cell = (int(cells[0][0]), int(cells[0][1]))
        n = len(np.unique(cells[:, 0] * grid.shape[1] + cells[:, 1]))
        where = f'row {cell[0]}, column {cell[1]}'
        answer = f'the {name} is at {where}' + (f' ({n} cells)' if n > 1 else '')
        return replace(out, answer=answer, referent=cell, landmarks=[name])

    def no_goal(self, grid: np.ndarray, instruction: str, command: Command, reason):
        """Return a grounding that sends no goal: a stop, a question, a decline."""
        zeros = np.zeros(grid.shape, dtype=np.float32)
        return Grounding(instruction, zeros, zeros, None, tokenize(instruction), None, [],
                         reason=reason, intent=command.intent)

    def judge(self, values: np.ndarray):
        """Return the best cell, its calibrated probability, and the next best with theirs."""
        return judged(values, self.temperature)

    def named(self, mentions: list[Mention]) -> list[str]:
        """Return the table's names of the landmarks mentioned, each once, in order."""
        return [self.entities.names[k] for k in dict.fromkeys(m.kind for m in mentions)]
