# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
A plain Python API over a trained model, for users who do not want topics.

    g = Grounder.from_checkpoint()                    # the packaged pw_t-rnet-attn
    result = g.ground(grid, "reach cell two below the westernmost rock")
    result.goal, result.values, result.relation_map, result.attention

The ROS grounder node is a thin adapter over this class.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
import torch

from .core.text import tokenize, UNK
from .models.checkpoints import load_checkpoint, Loaded
from .models.protocol import TextCode

DEFAULT_CHECKPOINT = 'pw_t-rnet-attn'


@dataclass
class Grounding:
    """One grounded instruction. Maps are (H, W) with row 0 = north."""

    instruction: str
    values: np.ndarray  # predicted value map
    relation_map: np.ndarray  # Z1 (the paper's interpretability view is |Z1|)
    goal: tuple[int, int]  # (row, col) of the best cell
    words: list[str]
    attention: list[float] | None  # per word, averaged over cell pairs (t-RNetAttn only)
    unknown_words: list[str]


class Grounder:
    def __init__(self, loaded: Loaded, cached_instructions: int = 64):
        """
        Wrap a loaded checkpoint.

        The text codes of the last `cached_instructions` instructions are kept (t-RNetAttn: the
        relation table over all kinds), since a node grounds the same instruction on new maps.
        """
        self.loaded, self.cached_instructions = loaded, cached_instructions
        self.model, self.vocab, self.entities = loaded.model, loaded.vocab, loaded.entities
        self.model.eval()
        self.text_codes: OrderedDict[str, TextCode] = OrderedDict()  # least recently used first

    @classmethod
    def from_checkpoint(cls, checkpoint: str = DEFAULT_CHECKPOINT) -> 'Grounder':
        return cls(load_checkpoint(checkpoint))

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
        if not tokenize(instruction):
            raise ValueError('instruction has no words')
        if all(i == UNK for i in self.vocab.encode(instruction)):
            raise ValueError(f'no word of the instruction {instruction!r} is in the vocabulary')

    @torch.no_grad()
    def text_code(self, instruction: str) -> TextCode:
        """Return the model's text code of an instruction, computed once while it is in use."""
        code = self.text_codes.pop(instruction, None)
        if code is None:
            code = self.model.text_code(torch.as_tensor(self.vocab.encode_batch([instruction])))
            if len(self.text_codes) >= self.cached_instructions:
                self.text_codes.popitem(last=False)
        self.text_codes[instruction] = code
        return code

    @torch.no_grad()
    def ground(self, grid: np.ndarray, instruction: str) -> Grounding:
        self.check(grid, instruction)
        grids = torch.as_tensor(np.asarray(grid, dtype=np.int64))[None]
        values, aux = self.model.ground(grids, self.text_code(instruction), return_aux=True)
        values = values[0].numpy()
        row, col = np.unravel_index(int(values.argmax()), values.shape)
        words = tokenize(instruction)
        attention = aux['attention']
        return Grounding(
            instruction,
            values,
            aux['relation_map'][0].numpy(),
            (int(row), int(col)),
            words,
            None if attention is None else attention[0].tolist(),
            [w for w in words if w not in self.vocab.index],
        )
