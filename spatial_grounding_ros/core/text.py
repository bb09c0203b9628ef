# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""Instruction text: tokenizer and vocabulary (padding and unknown-word ids reserved)."""

from __future__ import annotations

from collections import Counter
import re
from typing import Iterable

import numpy as np

PAD, UNK = 0, 1
PAD_TOKEN, UNK_TOKEN = '<pad>', '<unk>'
_WORD = re.compile(r"[a-z0-9]+(?:'[a-z]+)?")


def tokenize(text: str) -> list[str]:
    """Lower-case words and numbers; punctuation is dropped ("rock." == "rock")."""
    return _WORD.findall(text.lower())


class Vocabulary:
    """Word <-> id map built from training instructions. Id 0 pads, id 1 is any unknown word."""

    def __init__(self, words: Iterable[str]):
        self.words = [PAD_TOKEN, UNK_TOKEN] + [w for w in words if w not in (PAD_TOKEN, UNK_TOKEN)]
        self.index = {w: i for i, w in enumerate(self.words)}

    @classmethod
    def build(cls, instructions: Iterable[str], min_count: int = 1) -> 'Vocabulary':
        counts = Counter(w for text in instructions for w in tokenize(text))
        return cls(sorted(w for w, c in counts.items() if c >= min_count))

    def __len__(self) -> int:
        return len(self.words)

    def encode(self, text: str) -> list[int]:
        return [self.index.get(w, UNK) for w in tokenize(text)]

    def encode_batch(self, texts: list[str]) -> np.ndarray:
        """(B, L) int64 ids, right-padded with PAD to the longest instruction (at least 1)."""
        ids = [self.encode(t) or [UNK] for t in texts]
        out = np.full((len(ids), max(len(i) for i in ids)), PAD, dtype=np.int64)
        for row, seq in enumerate(ids):
            out[row, : len(seq)] = seq
        return out
