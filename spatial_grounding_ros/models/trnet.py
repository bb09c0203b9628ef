# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""t-RNet and t-RNetAttn: the text-conditioned relation network."""

from __future__ import annotations

import torch
from torch import nn

from .config import ModelConfig, neighbour_offsets, relation_param_count, relative_positions
from .encoders import (
    absent_names_unknown,
    EntityEncoder,
    kind_rows,
    kinds_per_map,
    present_kinds,
    TextEncoder,
)
from .far import FAR_LOG_COST, far_map, FAR_POSITION
from .head import build_head, outputs
from .map_cells import map_cells
from .protocol import Capabilities, EntityRows, RelationCode
from .relation import cell_pairs, kind_table, pair_relations
from .traces import traced


class TRNet(EntityRows, nn.Module):
    """
    Text-conditioned relation network.

    With attention (t-RNetAttn) the relation MLP's weights are decoded from h_ij = sum_k
    alpha_ij(k) h(k) for each cell pair; without it (t-RNet) from the mean of the LSTM outputs, the
    same for every pair.

    Two ways to the same numbers. The reference (pair_forward) scores every cell pair of the map.
    The fast way uses that a pair's score, attention included, depends only on the two cells'
    kinds, their offset and the instruction: text_code scores each (kind_i, kind_j, offset) once
    per instruction, a table whatever the map size, and ground reads each pair's score from it.
    forward takes whichever scores fewer rows; both give the same values and gradients. The two
    halves are models.relation's pair_relations and kind_table, and the far relation is
    models.far's far_map: this class holds the weights, passes them in and chooses the path.
    """

    def __init__(self, cfg: ModelConfig, attention: bool = True):
        super().__init__()
        self.cfg, self.attention = cfg, attention
        self.phi = EntityEncoder(cfg, pad=cfg.radius)
        self.text = TextEncoder(cfg, cfg.skip_unknown)
        self.decoder = nn.Linear(cfg.hidden, relation_param_count(cfg))  # h -> 263
        if attention:
            # project h(k) to 2k dims to score it against [phi(s_i); phi(s_j)]. Zero at
            # start: uniform attention, which makes the model exactly t-RNet (the decoder is
            # linear), so training can begin with the cheap attention-free forward.
            self.attn = nn.Linear(cfg.hidden, 2 * cfg.embed_dim, bias=False)
            nn.init.zeros_(self.attn.weight)
        self.attention_on = attention  # training may switch it off while attn is still 0
        self.head = build_head(cfg)
        sizes = [2 * cfg.embed_dim + 1, *cfg.mlp, 1]
        self.layer_shapes = list(zip(sizes[1:], sizes[:-1]))  # (out, in) per layer
        if cfg.far:
            self.far_log_cost = nn.Parameter(torch.tensor(FAR_LOG_COST))

    @staticmethod
    def supports(attention: bool = True) -> Capabilities:
        """Return what a TRNet built with or without `attention` supports."""
        return Capabilities(
            relation_attention=attention, far_relation=True, unseen_rows=True, distractor_rows=True
        )

    @property
    def capabilities(self) -> Capabilities:
        return self.supports(self.attention)

    def relations(self, phi_i: torch.Tensor, phi_j: torch.Tensor, text: tuple):
        """
        Score every pair of a map: centres phi_i (B, N, k) against phi_j (B, N, P, k).

        Returns r (B, N, P) and the attention over words (B, N, P, L) (None without it).
        """
        words, mask, mean = text  # (B, L, 30), (B, L), (B, 30)
        rel = relative_positions(self.cfg.radius).to(phi_j.device)
        if self.attention_on:  # each word's weights, mixed per pair by its attention
            return pair_relations(
                phi_i, phi_j, rel, self.decoder(words), self.layer_shapes, self.attn(words), mask
            )
        return pair_relations(phi_i, phi_j, rel, self.decoder(mean), self.layer_shapes)

    def table(self, kinds: torch.Tensor, kinds_j: torch.Tensor, text: tuple, rel: torch.Tensor):
        """
        Score every (kind_i, kind_j) of `kinds` x `kinds_j` at each position code of `rel` (P,).

        Returns r (B, Ki * Kj, P) and each row's attention over words, or None (kind_table).
        """
        words, mask, mean = text  # (B, L, 30), (B, L), (B, 30)
        embed, shapes = self.phi.embed.weight, self.layer_shapes
        if not self.attention_on:  # one 'word': t-RNet's weights, shared by every pair
            return kind_table(embed, kinds, kinds_j, rel, self.decoder(mean[:, None]), shapes)
        return kind_table(
            embed, kinds, kinds_j, rel, self.decoder(words), shapes, self.attn(words), mask
        )

    def forward(
        self,
        grids: torch.Tensor,
        tokens: torch.Tensor,
        return_aux: bool = False,
        reference: bool = False,
    ):
        """
        Value maps (B, H, W) for grids (B, H, W) and tokens (B, L).

        reference=True scores every cell pair of the maps (the definition); otherwise each
        map's relation table over the kinds it holds is used when it is the cheaper (a table
        row is a (kind_i, kind_j) pair with a column per offset, a map row a cell with its 8
        neighbours). Without attention that is when it has fewer rows than the maps have
        cells: a 10x10 map with all 12 kinds has 12 x 13 = 156 rows against 100 cells. With
        attention each of a map's pairs mixes the L words' weights, a table row mixes them
        once for all its offsets, so the table wins on any map but the smallest. With
        cfg.name_words, a name of a kind the map lacks reads as <unk> (absent_names_unknown).
        """
        if self.cfg.name_words:
            tokens = absent_names_unknown(grids, tokens, self.cfg)
        kinds = kinds_per_map(grids, self.phi.embed.num_embeddings, self.phi.off_map)
        n_kinds = kinds.shape[1]
        rows, cells = n_kinds * (n_kinds + 1), grids.shape[1] * grids.shape[2]
        offsets = len(neighbour_offsets(self.cfg.radius))
        words = tokens.shape[1] if self.attention_on else 0
        if reference or rows * (offsets + words) >= cells * offsets * max(words, 1):
            return self.pair_forward(grids, tokens, return_aux)
        return self.ground(grids, self.text_code(tokens, kinds), return_aux)

    def pair_forward(self, grids: torch.Tensor, tokens: torch.Tensor, return_aux: bool = False):
        """Score every cell against each of its 8 neighbours: the reference."""
        b, h, w = grids.shape
        # (B, N, k), (B, N, 8, k), from the map embedded with its off-map border
        phi_i, phi_j = cell_pairs(self.phi(grids), self.cfg.radius)
        text = self.text(tokens)
        r, attention = self.relations(phi_i, phi_j, text)  # (B, N, 8)
        z1 = r.max(dim=-1).values.view(b, h, w)
        far = None
        if self.cfg.far:  # its score has no offset term: a table over the kinds present
            kinds = present_kinds(grids, self.cfg.n_entities)
            far = self.far_relation(grids, kinds, self.far_table(text, kinds))
        values = self.head(z1, self.decoder(text[2])[:, -self.head.code_size:], far)  # h's last
        # how much each word mattered, averaged over all pairs
        word_attention = None if attention is None else attention.mean(dim=(1, 2))
        return outputs(values, z1, word_attention, return_aux)

    def text_code(self, tokens: torch.Tensor, kinds: torch.Tensor | None = None) -> RelationCode:
        """
        All that an instruction contributes, for maps of any size (compute_text_code).

        Over all kinds at inference (a grounder's, once per instruction) it runs as a trace
        per sentence length (models.traces): bit for bit the same, 0.7 -> 0.4 ms.
        """
        if kinds is not None or torch.is_grad_enabled() or torch.jit.is_tracing():
            return self.compute_text_code(tokens, kinds)
        code = traced(self, lambda: TracedTextCode(self), (tokens,), key=(self.attention_on,))
        kinds, relations, attention, head, far = code
        return RelationCode(
            kinds=kinds,
            relations=relations,
            attention=attention if self.attention_on else None,
            head=head,
            far=far if self.cfg.far else None,
        )

    def compute_text_code(
        self, tokens: torch.Tensor, kinds: torch.Tensor | None = None
    ) -> RelationCode:
        """
        All that an instruction contributes, for maps of any size.

        The relation table r over (kind_i, kind_j, offset) as (B, Ki * Kj, 8), row
        i * Kj + j; the attention over words per kind pair (B, Ki * Kj, L), the same at every
        offset (its score has no offset term), or None; and the head's code (B, code_size).
        The centre kinds are `kinds` (default: all), the neighbour kinds those and the off-map
        one: a caller that keeps this per instruction grounds it on any map with a gather and a
        max. `kinds` (B, K): a table of each instruction's own kinds (kinds_per_map).
        """
        if kinds is None:
            kinds = torch.arange(self.cfg.n_entities, device=tokens.device)
        off_map = kinds.new_full((*kinds.shape[:-1], 1), self.phi.off_map)
        kinds_j = torch.cat([kinds, off_map], -1)
        n_nbrs = len(neighbour_offsets(self.cfg.radius))
        text = self.text(tokens)
        # the far relation's position is a ninth column of the same rows: one pass scores both
        # (far_table's (kind_i, kind_j) are the rows whose j is not off the map)
        rel = relative_positions(self.cfg.radius).to(tokens.device)
        if self.cfg.far:
            rel = torch.cat([rel, rel.new_tensor([FAR_POSITION])])
        r, attention = self.table(kinds, kinds_j, text, rel)
        far = None
        if self.cfg.far:
            far = r[..., n_nbrs].unflatten(1, (kinds.shape[-1], kinds_j.shape[-1]))[..., :-1]
        return RelationCode(
            kinds=kinds,
            relations=r[..., :n_nbrs],
            attention=attention,
            head=self.decoder(text[2])[:, -self.head.code_size:],
            far=far,
        )

    def far_table(self, text: tuple, kinds: torch.Tensor) -> torch.Tensor:
        """Score each (kind_i, kind_j) of `kinds` with the far relation: (B, K, K)."""
        r, _ = self.table(kinds, kinds, text, torch.tensor([FAR_POSITION], device=kinds.device))
        return r.view(-1, kinds.shape[-1], kinds.shape[-1])

    def far_relation(
        self,
        grids: torch.Tensor,
        kinds: torch.Tensor,
        table: torch.Tensor,
        rows: torch.Tensor | None = None,
    ) -> torch.Tensor:
        """Return far.far_map with this model's cost; `rows`: the cells' kind_rows, if known."""
        if rows is None:
            rows = kind_rows(grids, kinds, self.phi.embed.num_embeddings)
        return far_map(grids, kinds, table, self.far_log_cost.exp(), rows)

    def ground(self, grids: torch.Tensor, code: RelationCode, return_aux: bool = False):
        """Value maps of grids (B, H, W) for a text_code of B instructions (or of 1 for all)."""
        b, h, w = grids.shape
        kinds, relations = code.kinds, code.relations  # (B or 1, Ki * Kj, P)
        p = relations.shape[2]
        # each pair's (kind_i, kind_j) row, i * Kj + j, with j the off-map row past the border
        cells = map_cells(grids, kinds, self.phi.embed.num_embeddings, self.cfg.radius, p)
        table = relations.flatten(1).expand(b, -1)  # a pair's row * P + its offset
        if cells.index is not None:
            # one gather of all offsets and amax, whose gradient splits among equal maxima
            z1 = table.gather(1, cells.index).view(b, h * w, p).amax(-1).view(b, h, w)
        else:  # offset by offset: the same maxima without (B, N, P) indices, 4x faster at 512^2
            z1 = None
            for offset, pair in enumerate(cells.pairs):
                r = table.gather(1, (pair * p + offset).view(b, -1))
                z1 = r if z1 is None else torch.maximum(z1, r, out=z1)
            z1 = z1.view(b, h, w)
        far = None
        if code.far is not None:
            far = self.far_relation(grids, kinds, code.far, cells.centre)
        values = self.head(z1, code.head.expand(b, -1), far)
        word_attention = None
        if return_aux and code.attention is not None:
            # the mean over the map's pairs: each kind pair's attention times its pair count
            counts = cells.counts().to(relations.dtype)
            word_attention = (counts.view(b, 1, -1) @ code.attention.expand(b, -1, -1))[
                :, 0
            ] / (p * h * w)
        return outputs(values, z1, word_attention, return_aux)


class TracedTextCode(nn.Module):
    """A TRNet's text code over all kinds as a trace records it: tensors only (empty for None)."""

    def __init__(self, model: TRNet):
        super().__init__()
        self.model = model

    def forward(self, tokens: torch.Tensor) -> tuple:
        code = self.model.compute_text_code(tokens)
        fields = (code.kinds, code.relations, code.attention, code.head, code.far)
        return tuple(tokens.new_zeros(0) if x is None else x for x in fields)
