# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
What every grid model offers its callers: its text code, and what it supports.

A model maps (grids (B, H, W), tokens (B, L)) to value maps, in two steps a caller may keep
apart: text_code(tokens) holds all that the instructions contribute, whatever the map size,
and ground(grids, code) applies it to maps (the Grounder keeps codes per instruction). Each
model's code is a dataclass of its own below.

Training, augmentation and the studies ask a model's Capabilities, declared by its class,
never its name: whether it attends over words per pair (so training may warm up without),
takes the far relation, and has entity rows for unseen and for distractor kinds.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Protocol, Union

import numpy as np
import torch


@dataclass(frozen=True)
class Capabilities:
    """What a grid model's architecture supports."""

    # attention over the words per cell pair, which starts uniform: training may run the
    # attention-free forward for a warm-up (the model's attention_on)
    relation_attention: bool = False
    # ModelConfig.far: a second relation map, each cell against every cell within reach
    far_relation: bool = False
    # its entity table holds ModelConfig.unseen_kinds rows no training map uses (EntityRows)
    unseen_rows: bool = False
    # its entity table holds ModelConfig.distractor_kinds rows, redrawn at every training step
    # (EntityRows.redraw_distractors)
    distractor_rows: bool = False


@dataclass(eq=False)
class RelationCode:
    """
    t-RNet's and t-RNetAttn's text code: a relation table per instruction.

    `relations` (B, Ki * Kj, P): the score of (kind_i, kind_j) at each of the P offsets, row
    i * Kj + j, with `kinds` (K,) or (B, K) the centre kinds and the neighbour kinds those and
    the off-map one. `attention` (B, Ki * Kj, L): each row's attention over the words (the same
    at every offset), None without attention. `head` (B, code_size): the output network's
    code. `far` (B, Ki, Ki): the far relation's table, None without it.
    """

    kinds: torch.Tensor
    relations: torch.Tensor
    attention: torch.Tensor | None
    head: torch.Tensor
    far: torch.Tensor | None


@dataclass(eq=False)
class KernelCode:
    """t-CNN's text code: a 3x3 kernel over the entity embeddings (B, k, 3, 3), the head's code."""

    kernels: torch.Tensor
    head: torch.Tensor


@dataclass(eq=False)
class TextVectorCode:
    """t-UVFA's text code: the text vector (B, uvfa_text) joined to every cell's state."""

    text: torch.Tensor


TextCode = Union[RelationCode, KernelCode, TextVectorCode]


class GridModel(Protocol):
    """The calls every grid model answers (models.registry builds them by name)."""

    @property
    def capabilities(self) -> Capabilities:
        ...

    def text_code(self, tokens: torch.Tensor) -> TextCode:
        ...

    def ground(self, grids: torch.Tensor, code: TextCode, return_aux: bool = False):
        ...


class EntityRows:
    """
    The extra rows of a model's entity table, for a model whose `phi` is an EntityEncoder.

    Mixed into the models whose Capabilities have unseen_rows and distractor_rows.
    """

    def unseen_kinds(self) -> list[int]:
        """Return the grid values of the unseen kinds this model has rows for."""
        return self.phi.unseen_ids

    def distractor_kinds(self) -> list[int]:
        """Return the grid values of this model's distractor kinds."""
        return self.phi.distractor_ids

    def redraw_distractors(self, draw: Callable[[tuple[int, int]], np.ndarray]) -> None:
        """Set the distractor kinds' embedding rows to `draw((rows, k))`, as a batch of rows."""
        self.phi.redraw_distractors(draw)
