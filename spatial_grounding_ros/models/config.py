# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The models' sizes and hyper-parameters (ModelConfig), and the neighbourhood they relate.

Sizes are the paper's (section 3.2, appendix A); PuddleWorld numbers in comments.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

import torch


def neighbour_offsets(radius: int) -> list[tuple[int, int]]:
    """
    Return the cells j around i, as (d_row, d_col).

    Radius 1 is the paper's 8 neighbours; the paper's footnote extends relations to cells further
    away (radius 2: 24 neighbours).
    """
    return [
        (dr, dc)
        for dr in range(-radius, radius + 1)
        for dc in range(-radius, radius + 1)
        if (dr, dc) != (0, 0)
    ]


def relative_positions(radius: int) -> torch.Tensor:
    """l_ij: a scalar code of j's position relative to i, evenly spaced in [-1, 1]."""
    return torch.linspace(-1.0, 1.0, len(neighbour_offsets(radius)))


@dataclass
class ModelConfig:
    """Hyper-parameters, all in one place (PuddleWorld values; ISI uses embed_dim 13)."""

    n_entities: int = 12  # entity kinds in the table (PuddleWorld: 12)
    vocab_size: int = 2  # words incl. <pad>, <unk>
    embed_dim: int = 7  # k: entity embedding (13 for ISI)
    word_dim: int = 15  # word embedding = LSTM input
    hidden: int = 30  # LSTM hidden size
    mlp: tuple = (10, 10)  # relation MLP hidden layers (output 1), tanh
    uvfa_text: int = 7  # t-UVFA text vector
    uvfa_channels: int = 16  # t-UVFA state encoder channels
    head: tuple = (8, 16, 32, 16, 8)  # output network: 3x3 conv channels before the last conv
    radius: int = 1  # relation neighbourhood (1: the paper's 8 neighbours)
    head_slope: float = 0.01  # negative slope of the head's ReLUs (0: plain ReLU)
    # G1, G2 rise by 1 every this many cells (0: span -1..1 whatever the size)
    gradient_cells: float = 0.0
    axial: bool = False  # the head's second layer also reads map-wide row/column maxima
    # a second relation map: each cell against every cell within FAR_REACH, its score the
    # relation MLP's at a 'far' position code minus a learned cost per squared cell of
    # distance ("the tree closest to the star")
    far: bool = False
    # the instruction scales and shifts the head's first-layer channels (FiLM): the output
    # network knows which geometry the instruction asks for
    head_text: bool = False
    # entity kinds held out of training (the robustness study's unseen objects), see EntityEncoder
    unseen_kinds: int = 10
    # kinds after those whose embeddings training redraws at every step: its distractor objects
    # (TrainConfig.distractors), so a model learns to pass over things it does not know
    distractor_kinds: int = 0
    # the text encoder reads past words outside its vocabulary (<unk>): the LSTM runs over the
    # known words alone, so an unknown word cannot move the goal
    skip_unknown: bool = False
    # per kind, the vocabulary ids of the words that name it (and their plurals): the model reads
    # a name of a kind its map lacks as an unknown word, since that landmark cannot be the one
    # meant; () reads every name as it is (TrainConfig.skip_absent_names sets it)
    name_words: tuple = ()

    # fields added after checkpoints were shipped, with the value those checkpoints had
    LATER_FIELDS = {
        'gradient_cells': 0.0,
        'axial': False,
        'unseen_kinds': 0,
        'head_text': False,
        'far': False,
        'distractor_kinds': 0,
        'skip_unknown': False,
        'name_words': (),
    }

    def to_dict(self) -> dict:
        d = asdict(self)
        d['mlp'], d['head'] = list(self.mlp), list(self.head)
        d['name_words'] = [list(words) for words in self.name_words]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> 'ModelConfig':
        d = {**cls.LATER_FIELDS, **d}
        missing = [f.name for f in fields(cls) if f.name not in d]
        if missing:
            raise ValueError(f'model config lacks {", ".join(missing)}')
        name_words = tuple(tuple(int(i) for i in words) for words in d['name_words'])
        return cls(
            **{**d, 'mlp': tuple(d['mlp']), 'head': tuple(d['head']), 'name_words': name_words}
        )


def head_code_size(channels: tuple, film: bool) -> int:
    """
    Return the size of what the instruction gives an output network of `channels`.

    3 gradient coefficients, and with `film` a scale and a shift per first-layer channel.
    """
    return 3 + (2 * channels[0] if film and channels else 0)


def relation_param_count(cfg: ModelConfig) -> int:
    """
    Size of h: weights of f (no biases, as the paper counts) plus the head's code.

    (2k+1)*10 + 10*10 + 10*1 + 3 = 263 for k = 7, 383 for k = 13 (without head_text).
    """
    sizes = [2 * cfg.embed_dim + 1, *cfg.mlp, 1]
    weights = sum(a * b for a, b in zip(sizes[:-1], sizes[1:]))
    return weights + head_code_size(cfg.head, cfg.head_text)
