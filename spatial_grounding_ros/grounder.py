"""
A plain Python API over a trained model, for users who do not want topics.

    g = Grounder.from_checkpoint()                    # the packaged pw_t-rnet-attn
    result = g.ground(grid, "reach cell two below the westernmost rock")
    result.goal, result.confidence, result.reason, result.values, result.alternatives

    kitchen = Grounder.from_checkpoint(entities='kitchen.yaml')  # a table of your own

A grid may use any entity table: the landmarks an instruction names (by name, alias, plural
or a one-letter typo) are grounded as the model's own kinds (core/lexicon.py). When the
table and the map show that no cell fits (a landmark that is not there, a name no kind has,
a cell past the edge, several landmarks named as one, an obstacle), or the model is unsure,
the grounding declines: `goal` is None and `reason` says why (core/checks.py).

The ROS grounder node is a thin adapter over this class.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from .core.checks import named_sides, structural_reason
from .core.entities import EntityTable, PUDDLEWORLD_NONUNIQUE, PUDDLEWORLD_UNIQUE
from .core.footprints import reduce_footprints
from .core.lexicon import Lexicon, Mention, Translation
from .core.text import tokenize, UNK
from .core.units import offsets
from .core.wording import (
    canonical,
    cell_for_fixed_target,
    count_first,
    drop_unknown,
    reworded,
    side_of_it,
    tidy,
    unpossessed,
    wording_words,
)
from .data.augment import MIRROR_IMAGES, mirror_instruction
from .models.checkpoints import load_checkpoint, Loaded
from .models.protocol import TextCode

DEFAULT_CHECKPOINT = 'pw_t-rnet-attn'
# the map as it is, then its mirror images (the map axes each flips), as training mirrors its
# human examples (data/augment.py)
IMAGES = ((), *MIRROR_IMAGES)
# maps of up to this many cells (128x128) are grounded with their mirror images: four times the
# work, 2.6 ms against 0.6 ms at 10x10 and 28 against 15 ms at 64x64, but 5-7 times at 256x256
# and more, where the tiled output network dominates (docs/benchmarks.md)
MIRROR_AVERAGE_CELLS = 128 * 128


# how many next-best cells a grounding reports
ALTERNATIVES = 3
# the reasons a grounding may decline with (core/checks.py has the structural ones)
REASONS = (
    'referent-missing',
    'unknown-landmark',
    'off-map',
    'ambiguous',
    'unsupported',
    'goal-on-obstacle',
    'low-confidence',
)


@dataclass
class Grounding:
    """
    One grounded instruction. Maps are (H, W) with row 0 = north.

    `goal` is None when the grounding declines, and `reason` then says why, as a code and
    words ('referent-missing: rock'); `best` is the model's best cell all the same.
    `confidence` is the calibrated chance that `best` is the cell meant; `alternatives` the
    next best cells with theirs.
    """

    instruction: str
    values: np.ndarray  # predicted value map
    relation_map: np.ndarray  # Z1 (the paper's interpretability view is |Z1|)
    goal: tuple[int, int] | None  # (row, col) of the cell to go to; None: declined
    words: list[str]
    attention: list[float] | None  # per word, averaged over cell pairs (t-RNetAttn only)
    unknown_words: list[str]
    best: tuple[int, int] = (0, 0)
    confidence: float = 0.0
    reason: str | None = None
    alternatives: list[tuple[tuple[int, int], float]] = field(default_factory=list)
    landmarks: list[str] = field(default_factory=list)  # the table's names the words named
    # the cell of a named landmark nearest the best cell (a goal can face it), or None
    referent: tuple[int, int] | None = None
    model_instruction: str = ''  # what the model read: the landmarks in its own names
    # what the instruction asks: 'go', 'stop', 'question', 'sequence', 'negation', 'unsupported'
    intent: str = 'go'
    # 'sequence': one grounding per step, in order (`goal` is the first step's goal)
    steps: list[Grounding] = field(default_factory=list)
    answer: str | None = None  # 'question': the answer in words (`referent`: the landmark's cell)

    @property
    def reason_code(self) -> str | None:
        """Return the reason's code alone ('referent-missing'), or None."""
        return None if self.reason is None else self.reason.split(':')[0]


def resolve_table(entities: str | Path | EntityTable | None) -> EntityTable | None:
    """Return an entity table given as a table, a YAML path or None."""
    if entities is None or isinstance(entities, EntityTable):
        return entities
    return EntityTable.from_yaml(entities)


def shifted(values: np.ndarray, offset: tuple[int, int]) -> np.ndarray:
    """Return a value map moved by (rows, cols), the cells it leaves at its lowest value."""
    if offset == (0, 0):
        return values
    out = np.full_like(values, values.min())
    h, w = values.shape
    dr, dc = offset
    if abs(dr) < h and abs(dc) < w:
        out[max(dr, 0):h + min(dr, 0), max(dc, 0):w + min(dc, 0)] = values[
            max(-dr, 0):h + min(-dr, 0), max(-dc, 0):w + min(-dc, 0)
        ]
    return out


def imaged(grid: np.ndarray, images) -> torch.Tensor:
    """Return the map's `images` (each the axes it flips) as one batch (I, H, W)."""
    return torch.as_tensor(np.stack([np.flip(grid, axes) for axes in images]))


def averaged(values: np.ndarray, images) -> np.ndarray:
    """Return the mean of the images' value maps (I, H, W), each flipped back."""
    return np.mean([np.flip(v, axes) for v, axes in zip(values, images)], 0)


def nearest_cell(grid: np.ndarray, kinds: list[int], cell: tuple[int, int]):
    """Return the cell of any of `kinds` nearest `cell` (Euclidean), or None."""
    where = np.argwhere(np.isin(grid, kinds))
    if not len(where):
        return None
    nearest = where[((where - np.asarray(cell)) ** 2).sum(1).argmin()]
    return int(nearest[0]), int(nearest[1])


class Grounder:
    def __init__(
        self,
        loaded: Loaded,
        entities: EntityTable | None = None,
        min_confidence: float = 0.0,
        cached_instructions: int = 64,
        cell_size: float | None = None,
        kinds_by: str = 'name',
        mirror_average_cells: int = MIRROR_AVERAGE_CELLS,
    ):
        """
        Wrap a loaded checkpoint, for maps in `entities` (default: the checkpoint's table).

        A model trained on PuddleWorld reads any table (core/lexicon.Translation); others
        only their own. `min_confidence` (0..1): a grounding less sure than this declines.
        `cell_size`: metres per cell, for distances in metres (core/units.py); a table's
        landmarks may cover several cells (EntityTable.has_footprints, core/footprints.py).
        `kinds_by`: how the model's own landmark names take its kinds (lexicon.KINDS_BY).
        `mirror_average_cells`: on maps of at most this many cells the value map is the mean of
        the model's over the map and its three mirror images, each read with its direction
        words swapped (IMAGES, in one batch): where the model is unsure of a cell, its mirror
        images seldom are unsure the same way (0: never). The text codes of the last
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
        self.mirror_average_cells = mirror_average_cells
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
        self.known = frozenset(self.vocab.words[2:]) | wording_words()
        # calibration: confidence is the softmax of the values at this temperature
        self.temperature = float(loaded.header.get('calibration', {}).get('temperature', 1.0))
        self.model.eval()
        # instruction -> (its words for the model, {images: text code}); least recently used
        # first
        self.text_codes: OrderedDict[str, tuple[str, dict]] = OrderedDict()

    @classmethod
    def from_checkpoint(
        cls,
        checkpoint: str | Path = DEFAULT_CHECKPOINT,
        entities: str | Path | EntityTable | None = None,
        min_confidence: float = 0.0,
        cell_size: float | None = None,
        mirror_average_cells: int = MIRROR_AVERAGE_CELLS,
    ) -> 'Grounder':
        """Load a packaged checkpoint by name or a path, for maps of any entity table."""
        return cls(
            load_checkpoint(checkpoint),
            resolve_table(entities),
            min_confidence,
            cell_size=cell_size,
            mirror_average_cells=mirror_average_cells,
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
        named = {i for m in self.lexicon.mentions(words) for i in range(m.start, m.end)}
        if not named and all(i == UNK for i in self.vocab.encode(instruction)):
            raise ValueError(f'no word of the instruction {instruction!r} is in the vocabulary')

    @torch.no_grad()
    def text_code(self, instruction: str, images: tuple = IMAGES) -> tuple[str, TextCode]:
        """
        Return what the model reads of an instruction (reword) and its text code for `images`.

        The code holds the instruction as said of each image of the map (IMAGES: the first is
        the instruction as it is; large maps take IMAGES[:1]). Each is computed once, when a
        map first needs it, while the instruction is in use.
        """
        cached = self.text_codes.pop(instruction, None)
        if cached is None:
            cached = self.reword(instruction), {}
            if len(self.text_codes) >= self.cached_instructions:
                self.text_codes.popitem(last=False)
        self.text_codes[instruction] = cached
        words, codes = cached
        if images not in codes:
            # encoded as a batch of all the images' wordings, so that the first image's tokens
            # carry the same padding whichever images a map takes
            said = [mirror_instruction(words, axes) for axes in IMAGES]
            tokens = torch.as_tensor(self.vocab.encode_batch(said))
            codes[images] = self.model.text_code(tokens[: len(images)])
        return words, codes[images]

    @torch.no_grad()
    def ground(
        self, grid: np.ndarray, instruction: str, cell_size: float | None = None
    ) -> Grounding:
        """
        Ground an instruction on a grid of this grounder's table.

        `cell_size` (metres per cell; default: the grounder's) turns distances in metres
        into cells; a distance in metres without one raises ValueError.
        """
        self.check(grid, instruction)
        grid = np.asarray(grid, dtype=np.int64)
        spoken = count_first(unpossessed(instruction))  # the landmark's side, a count after it
        distances = offsets(spoken, self.cell_size if cell_size is None else cell_size)
        words = tokenize(distances.text)
        if self.translation is not None:
            translated = self.translation(grid, distances.model_text)
            model_grid, model_text = translated.grid, translated.instruction
            mentions = list(translated.mentions)
            if self.entities.has_footprints:
                model_grid = self.anchored(model_grid, translated, distances.model_text)
        else:
            model_text = distances.model_text
            model_grid, mentions = grid, self.lexicon.mentions(tokenize(model_text))
        images = IMAGES if model_grid.size <= self.mirror_average_cells else IMAGES[:1]
        model_text, code = self.text_code(model_text, images)
        values, aux = self.model.ground(imaged(model_grid, images), code, True)
        values = shifted(averaged(values.numpy(), images), distances.extra)
        best, confidence, alternatives = self.judge(values)
        reason = structural_reason(self.entities, grid, *reworded(words, mentions), self.known)
        if reason is None and int(grid[best]) in self.entities.obstacles:
            reason = 'goal-on-obstacle'
        if reason is None and confidence < self.min_confidence:
            reason = f'low-confidence: {confidence:.2f} < {self.min_confidence:.2f}'
        attention = aux['attention']
        named = {i for m in mentions for i in range(m.start, m.end)}
        return Grounding(
            instruction,
            values,
            aux['relation_map'][0].numpy(),
            None if reason else best,
            words,
            None if attention is None else attention[0].tolist(),
            [w for i, w in enumerate(words) if w not in self.known and i not in named],
            best=best,
            confidence=confidence,
            reason=reason,
            alternatives=alternatives,
            landmarks=self.named(mentions),
            referent=nearest_cell(grid, [m.kind for m in mentions], best),
            model_instruction=model_text,
        )

    def anchored(self, model_grid: np.ndarray, translated, text: str) -> np.ndarray:
        """
        Return the model's grid with each named landmark's footprint reduced to its anchor.

        The side each landmark's offset leaves it on is read from the words before its
        mention (core/footprints.py).
        """
        sides = named_sides(*reworded(tokenize(text), list(translated.mentions)))
        sides = {translated.kinds[k]: side for k, side in sides.items() if k in translated.kinds}
        return reduce_footprints(model_grid, sides, self.model_entities.obstacles[0])

    def reword(self, text: str) -> str:
        """
        Return an instruction in the words the model learned (core/wording.py).

        Other wordings of a relation, a unit or a verb become the model's, filler goes, and
        so does every word the model never saw, so that none can move the goal. The model's
        own landmark names are never reworded, but a target whose row and column two
        landmarks fix is said as "cell" (wording.cell_for_fixed_target), a side of "its"
        landmark is said of it (wording.side_of_it), and a verb past the opening or a repeated
        article is left out (wording.tidy).
        """
        words = tokenize(text)
        names = [i for i, w in enumerate(words) if w in self.model_entities.names]
        words = tidy(drop_unknown(canonical(words, names), self.vocab.index))
        names = [i for i, w in enumerate(words) if w in self.model_entities.names]
        words = side_of_it(words, names)
        names = [i for i, w in enumerate(words) if w in self.model_entities.names]
        return ' '.join(cell_for_fixed_target(words, names))

    def judge(self, values: np.ndarray):
        """Return the best cell, its calibrated probability, and the next best with theirs."""
        flat = values.reshape(-1).astype(np.float64) / self.temperature
        p = np.exp(flat - flat.max())
        p /= p.sum()
        best = int(np.argmax(flat))  # the first of equal maxima, as numpy's argmax
        k = min(ALTERNATIVES + 1, p.size)
        top = np.argpartition(-p, k - 1)[:k]
        others = [i for i in top[np.argsort(-p[top], kind='stable')] if i != best][:ALTERNATIVES]

        def cell(i):
            return tuple(int(x) for x in np.unravel_index(i, values.shape))

        return cell(best), float(p[best]), [(cell(i), float(p[i])) for i in others]

    def named(self, mentions: list[Mention]) -> list[str]:
        """Return the table's names of the landmarks mentioned, each once, in order."""
        return [self.entities.names[k] for k in dict.fromkeys(m.kind for m in mentions)]
