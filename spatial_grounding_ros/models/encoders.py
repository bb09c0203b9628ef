# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""The text encoder (words -> LSTM), the entity encoder phi, and the kinds a map holds."""

from __future__ import annotations

from typing import Callable

import numpy as np
import torch
from torch import nn
import torch.nn.functional as F

from .config import ModelConfig, neighbour_offsets
from ..core.text import PAD, UNK


class TextEncoder(nn.Module):
    """
    Word embedding -> LSTM; per-word outputs h(k), the mask of words read, and their mean.

    With `skip_unknown` (ModelConfig.skip_unknown) the LSTM runs over the known words alone,
    packed to the front, and each output goes back to its word's place: an unknown word
    (<unk>) gets no output and no attention, and the words around it read as if it were not
    there.
    """

    def __init__(self, cfg: ModelConfig, skip_unknown: bool = False):
        super().__init__()
        self.embed = nn.Embedding(cfg.vocab_size, cfg.word_dim, padding_idx=PAD)
        self.lstm = nn.LSTM(cfg.word_dim, cfg.hidden, batch_first=True)
        self.skip_unknown = skip_unknown

    def forward(self, tokens: torch.Tensor):
        mask = tokens != PAD
        if not self.skip_unknown:
            mask[:, 0] = True  # an empty instruction still has one (unknown) word
            words, _ = self.lstm(self.embed(tokens))
        else:
            mask &= tokens != UNK
            mask[:, 0] |= ~mask.any(1)  # nothing known: its first word is read
            # the words read first, in their order; the rest become padding after them
            order = torch.argsort((~mask).to(torch.uint8), dim=1, stable=True)
            packed = tokens.gather(1, order).masked_fill(~mask.gather(1, order), PAD)
            read, _ = self.lstm(self.embed(packed))
            words = torch.zeros_like(read).scatter(1, order[..., None].expand_as(read), read)
        words = words * mask.unsqueeze(-1)
        mean = words.sum(1) / mask.sum(1, keepdim=True)
        return words, mask, mean


def absent_names_unknown(grids: torch.Tensor, tokens: torch.Tensor, cfg: ModelConfig):
    """
    Return tokens (B, L) with each word that names only kinds its map (B, H, W) lacks as <unk>.

    `cfg.name_words` holds each kind's words. Such a landmark cannot be the one meant, so a
    model that reads past unknown words (skip_unknown) passes over its name, as it would
    over any word it never saw; a word that also names a kind on the map stays.
    """
    n = cfg.n_entities
    names = torch.zeros(n, cfg.vocab_size, dtype=torch.bool, device=tokens.device)
    for kind, words in enumerate(cfg.name_words):
        names[kind, list(words)] = True
    # the kinds each map holds; unseen and distractor kinds (n and up) name nothing
    present = torch.zeros(len(grids), n + 1, device=tokens.device)
    present.scatter_(1, grids.flatten(1).clamp(max=n), 1.0)
    said_by_present = (present[:, :n] @ names.float()) > 0  # (B, V)
    absent = names.any(0)[tokens] & ~said_by_present.gather(1, tokens)
    return tokens.masked_fill(absent, UNK)


# Seed of the unseen kinds' embedding rows: the same rows in every model and every checkpoint.
UNSEEN_ROWS_SEED = 1010


def unseen_kind_ids(n_entities: int, count: int) -> list[int]:
    """Grid values of the first `count` unseen kinds: after the kinds and the off-map row."""
    return list(range(n_entities + 1, n_entities + 1 + count))


def distractor_kind_ids(cfg: ModelConfig) -> list[int]:
    """Grid values of the distractor kinds: after the unseen ones, never one of theirs."""
    first = cfg.n_entities + 1 + cfg.unseen_kinds
    return list(range(first, first + cfg.distractor_kinds))


class EntityEncoder(nn.Module):
    """
    phi.

    An embedding per entity index, plus one learned 'off the map' entity that pads the border so
    edge cells have a full neighbourhood too.

    Rows n+1 .. n+U are `cfg.unseen_kinds` kinds that no training map holds (the robustness
    study's unseen objects, `unseen_kind_ids`): training never touches them (an embedding row
    that is never looked up gets no gradient, and Adam leaves it where it was), so they stay
    at nn.Embedding's own initial distribution, N(0, 1), drawn from a generator of their own
    (UNSEEN_ROWS_SEED). Their own generator keeps the global random stream, and with it the
    initialisation of everything else, as it was before these rows existed. The
    `cfg.distractor_kinds` rows after them are training's distractors, redrawn from the same
    N(0, 1) at every step (augment.add_distractors): other draws than the unseen rows'.
    """

    def __init__(self, cfg: ModelConfig, pad: int = 1):
        super().__init__()
        self.off_map, self.pad = cfg.n_entities, pad
        self.embed = nn.Embedding(cfg.n_entities + 1, cfg.embed_dim)
        unseen = torch.randn(
            cfg.unseen_kinds,
            cfg.embed_dim,
            generator=torch.Generator().manual_seed(UNSEEN_ROWS_SEED),
        )
        distractors = torch.zeros(cfg.distractor_kinds, cfg.embed_dim)  # redrawn each step
        self.embed.weight = nn.Parameter(torch.cat([self.embed.weight.data, unseen, distractors]))
        self.embed.num_embeddings += cfg.unseen_kinds + cfg.distractor_kinds
        self.unseen_ids = unseen_kind_ids(cfg.n_entities, cfg.unseen_kinds)
        self.distractor_ids = distractor_kind_ids(cfg)

    def redraw_distractors(self, draw: Callable[[tuple[int, int]], np.ndarray]) -> None:
        """Set the distractor rows to `draw((rows, k))`: new draws, never learned."""
        weight = self.embed.weight
        with torch.no_grad():
            weight[self.distractor_ids] = torch.from_numpy(
                draw((len(self.distractor_ids), weight.shape[1]))
            ).to(weight)

    def with_unseen_rows(self, weight: torch.Tensor) -> torch.Tensor:
        """
        Complete a saved embedding `weight` that lacks some unseen rows with this encoder's.

        Checkpoints written before the unseen rows existed hold n+1 rows; they get the same
        deterministic rows a model trained with them has, so every checkpoint sees the same
        unseen objects.
        """
        return torch.cat([weight, self.embed.weight.data[len(weight):]])

    def pad_grid(self, grids: torch.Tensor) -> torch.Tensor:
        """(B,H,W) -> (B,H+2p,W+2p) entity indices, the border off the map."""
        p = self.pad
        return F.pad(grids, (p, p, p, p), value=self.off_map)

    def forward(self, grids: torch.Tensor) -> torch.Tensor:
        """(B,H,W) -> (B,H+2p,W+2p,k) embeddings of the border-padded grid."""
        return self.embed(self.pad_grid(grids))


def shifted(padded: torch.Tensor, radius: int) -> list[torch.Tensor]:
    """
    Each cell's neighbour at every offset, in neighbour_offsets order.

    (B, H+2r, W+2r, ...) padded by `radius` -> one (B, H, W, ...) view per offset: the work is
    per offset, never per cell.
    """
    height, width = padded.shape[1] - 2 * radius, padded.shape[2] - 2 * radius
    return [
        padded[:, radius + dr:radius + dr + height, radius + dc:radius + dc + width]
        for dr, dc in neighbour_offsets(radius)
    ]


def present_kinds(grids: torch.Tensor, n_entities: int) -> torch.Tensor:
    """Return the entity kinds in `grids`, ascending (a count, not a sort: cheap on big maps)."""
    return torch.bincount(grids.flatten(), minlength=n_entities).nonzero().flatten()


def kind_rows(grids: torch.Tensor, kinds: torch.Tensor, n_kinds: int) -> torch.Tensor:
    """
    Return each cell's row in a table over `kinds`, (B, H*W); a kind it lacks: an error.

    `kinds` (K,): one table for every map; (B, K): one per map. `n_kinds`: the entity table's
    rows.
    """
    kinds = kinds.expand(len(grids), -1)  # a shared table: the same kinds for every map
    row = torch.full((len(grids), n_kinds), -1, device=grids.device)
    row.scatter_(1, kinds, torch.arange(kinds.shape[1], device=grids.device).expand_as(kinds))
    cells = row.gather(1, grids.flatten(1))
    if cells.min() < 0:
        missing = sorted(set(grids.flatten(1)[cells < 0].tolist()))
        raise ValueError(f'the relation table lacks entity kinds {missing} of the grid')
    return cells


def kinds_per_map(grids: torch.Tensor, n_kinds: int, off_map: int) -> torch.Tensor:
    """
    Return each map's kinds (B, K), ascending, K the most any map of `grids` (B, H, W) holds.

    A map with fewer is padded with kinds it does not hold (never `off_map`, the neighbour
    kind past the border): their table rows are scored and never read. `n_kinds`: the
    entity table's rows, unseen and distractor kinds included.
    """
    b = grids.shape[0]
    held = torch.zeros(b, n_kinds, dtype=torch.int8, device=grids.device)
    held.scatter_(1, grids.flatten(1), 1)
    held[:, off_map] = -1  # last in the order below: never a padding kind
    count = int(held.eq(1).sum(1).max())
    # held kinds first, then the absent ones, each ascending (a stable sort)
    return held.argsort(dim=1, descending=True, stable=True)[:, :count]
