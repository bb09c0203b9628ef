# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""t-RNet and t-RNetAttn: the text-conditioned relation network."""

from __future__ import annotations

import torch
from torch import nn
import torch.nn.functional as F

from .config import ModelConfig, neighbour_offsets, relation_param_count, relative_positions
from .encoders import EntityEncoder, kinds_per_map, present_kinds, shifted, TextEncoder
from .far import (
    FAR_BEYOND,
    FAR_CHUNK_CELLS,
    FAR_LOG_COST,
    FAR_PAIRS,
    FAR_POSITION,
    FAR_REACH,
    pair_distances,
    squared_distances,
)
from .head import build_head, outputs
from .relation import tanh


class TRNet(nn.Module):
    """
    Text-conditioned relation network.

    With attention (t-RNetAttn) the relation MLP's weights are decoded from h_ij = sum_k
    alpha_ij(k) h(k) for each cell pair; without it (t-RNet) from the mean of the LSTM outputs, the
    same for every pair.

    Two ways to the same numbers. The reference (pair_forward) scores every cell pair of the map.
    The fast way uses that a pair's score, attention included, depends only on the two cells'
    kinds, their offset and the instruction: text_code scores each (kind_i, kind_j, offset) once
    per instruction, a table whatever the map size, and ground reads each pair's score from it.
    forward takes whichever scores fewer rows; both give the same values and gradients.
    """

    def __init__(self, cfg: ModelConfig, attention: bool = True):
        super().__init__()
        self.cfg, self.attention = cfg, attention
        self.phi = EntityEncoder(cfg, pad=cfg.radius)
        self.text = TextEncoder(cfg)
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

    def split_params(self, params: torch.Tensor) -> list[torch.Tensor]:
        """
        Cut a parameter vector (..., 263) into the relation MLP's weights (..., out, in).

        One split, not a slice per layer: a slice's backward fills a zero tensor of the
        vector's size, per layer.
        """
        sizes = [out * inp for out, inp in self.layer_shapes]
        parts = params.split([*sizes, params.shape[-1] - sum(sizes)], -1)
        return [part.unflatten(-1, shape) for part, shape in zip(parts, self.layer_shapes)]

    @staticmethod
    def relation_mlp(
        weights: list[torch.Tensor], x: torch.Tensor, attention: torch.Tensor | None
    ) -> torch.Tensor:
        """
        Compute r = W3 tanh(W2 tanh(W1 x)) over pairs' inputs x (B, N, P, in).

        Without attention the weights are one set per map, (B, out, in). With attention the
        pair (i, j) uses W_ij = sum_k alpha_ij(k) W(k), the weights decoded from each word k
        (B, L, out, in), attention (B, N, P, L): W_ij x = sum_k alpha_ij(k) (W(k) x), one
        matmul per word and a weighted sum, never a weight matrix per pair.
        """
        if not weights:
            return x.squeeze(-1)
        if attention is None:
            # one weight set per map: each layer is one bmm of (out, in) by the pairs as
            # columns, (B, in, N * P); 2x faster than by N * P rows of `in`
            b, n, p, _ = x.shape
            x = x.reshape(b, n * p, -1).transpose(1, 2)
            for w in weights[:-1]:
                x = tanh(torch.bmm(w, x))
            return torch.bmm(weights[-1], x).view(b, n, p)
        for n, w in enumerate(weights):
            x = (attention.unsqueeze(-1) * torch.einsum('bnpi,bloi->bnplo', x, w)).sum(-2)
            if n < len(weights) - 1:
                x = tanh(x)
        return x.squeeze(-1)

    def relations(self, phi_i: torch.Tensor, phi_j: torch.Tensor, text: tuple):
        """
        Score every pair of a map: centres phi_i (B, N, k) against phi_j (B, N, P, k).

        Returns r (B, N, P) and the attention over words (B, N, P, L) (None without it).
        """
        words, mask, mean = text  # (B, L, 30), (B, L), (B, 30)
        rel = relative_positions(self.cfg.radius).to(phi_j.device)
        k = phi_j.shape[-1]
        attention = None
        if self.attention_on:
            # alpha_ij(k) ~ exp(h(k)^T A [phi_i; phi_j]); the score splits into an i part and
            # a j part, so it costs (B, N, L) + (B, N, P, L), not a product over all three.
            q = self.attn(words)  # (B, L, 2k)
            score = torch.einsum('bnd,bld->bnl', phi_i, q[..., :k]).unsqueeze(2) + torch.einsum(
                'bnpd,bld->bnpl', phi_j, q[..., k:]
            )
            score = score.masked_fill(~mask[:, None, None, :], float('-inf'))
            attention = score.softmax(-1)  # (B, N, P, L)
            # the decoder is linear and sum_k alpha = 1, so decoding h_ij equals the
            # alpha-weighted sum of the words' decoded parameters
            weights = self.split_params(self.decoder(words))  # (B, L, out, in) per layer
        else:
            weights = self.split_params(self.decoder(mean))  # (B, out, in) per layer
        first = self.first_layer(weights[0], phi_i, phi_j, rel, attention)
        return self.relation_mlp(weights[1:], tanh(first), attention), attention

    @staticmethod
    def first_layer(
        w1: torch.Tensor,
        phi_i: torch.Tensor,
        phi_j: torch.Tensor,
        rel: torch.Tensor,
        attention: torch.Tensor | None,
    ) -> torch.Tensor:
        """
        Compute W1 [phi_i; phi_j; l] for every pair: (B, N, P, out).

        The layer is linear, so it splits into an i term, a j term and a position term, each
        computed where it varies: per cell, per pair and per offset. No pair meets the
        (2k+1)-wide weight, which takes about 30% off the relation MLP's work on a map
        (PuddleWorld: 260 -> 180 multiply-adds a pair). With attention the words' terms are
        mixed by it, per pair.
        """
        b, m, p, k = phi_j.shape
        w_i, w_j, w_rel = w1[..., :k], w1[..., k:2 * k], w1[..., 2 * k]
        if attention is None:
            # one set of weights per map, (B, out, in): computed with the pairs as columns,
            # (B, out, N, P), the layout relation_mlp's bmm reads without a copy
            term_i = torch.bmm(w_i, phi_i.transpose(1, 2))[..., None]
            term_j = torch.bmm(w_j, phi_j.reshape(b, m * p, k).transpose(1, 2))
            first = term_i + term_j.view(b, -1, m, p) + w_rel[:, :, None, None] * rel
            return first.permute(0, 2, 3, 1)
        # per word (B, L, out, in): each term for every word, then the attention-weighted sum
        term_i = torch.einsum('bnd,blod->bnlo', phi_i, w_i)
        term_j = torch.einsum('bnpd,blod->bnplo', phi_j, w_j)
        return (
            torch.einsum('bnpl,bnlo->bnpo', attention, term_i)
            + torch.einsum('bnpl,bnplo->bnpo', attention, term_j)
            + rel[:, None] * torch.einsum('bnpl,blo->bnpo', attention, w_rel)
        )

    def table(self, kinds: torch.Tensor, kinds_j: torch.Tensor, text: tuple, rel: torch.Tensor):
        """
        Score every (kind_i, kind_j) of `kinds` x `kinds_j` at each position code of `rel` (P,).

        `kinds` and `kinds_j` are (K,), one table for every instruction, or (B, K), one each.
        Returns r (B, Ki * Kj, P), row i * Kj + j, and the attention over words of each row
        (B, Ki * Kj, L), or None without attention. A pair's attention has no position term,
        so a row mixes the words' weights once for all its positions, where a map's pairs
        would each mix their own. The first layer splits into an i, a j and a position term
        (first_layer), here computed per kind and per word before the mix. t-RNet is the
        same computation with one 'word', the LSTM outputs' mean, at weight 1.
        """
        words, mask, mean = text  # (B, L, 30), (B, L), (B, 30)
        embed = self.phi.embed.weight
        b, k = len(words), embed.shape[1]
        # (B, Ki, k), (B, Kj, k)
        phi_i, phi_j = (embed[kinds].expand(b, -1, -1) for kinds in (kinds, kinds_j))
        if not self.attention_on:
            words = mean[:, None]  # one 'word': t-RNet's weights, shared by every pair
        # each word's relation MLP, (B, L, out, in) per layer
        w1, *later_layers = self.split_params(self.decoder(words))
        n_words, out = w1.shape[1:3]
        # each kind's i and j terms for every word: (B, Ki, L, out), (B, Kj, L, out)
        term_i = (phi_i @ w1[..., :k].flatten(1, 2).mT).unflatten(-1, (n_words, out))
        term_j = (phi_j @ w1[..., k:2 * k].flatten(1, 2).mT).unflatten(-1, (n_words, out))
        # the later layers' weights side by side, each as (in, out): x @ w, no transpose
        later = torch.cat([w.mT.flatten(-2) for w in later_layers], -1)  # (B, L, 110)
        if self.attention_on:
            # alpha ~ exp(h^T A [phi_i; phi_j]): an i part and a j part, (B, L, Ki, Kj). The
            # softmax runs over dim 1: this torch's CPU softmax is 16x slower over a last
            # dimension of about 12 (2 ms for a training batch)
            q = self.attn(words)  # (B, L, 2k)
            score = (q[..., :k] @ phi_i.mT)[..., :, None] + (q[..., k:] @ phi_j.mT)[..., None, :]
            alpha = score.masked_fill(~mask[:, :, None, None], float('-inf')).softmax(1)
            # the terms mixed per (kind_i, kind_j): (B, Ki, Kj, out)
            fixed = alpha.permute(0, 2, 3, 1) @ term_i + (
                alpha.permute(0, 3, 2, 1) @ term_j
            ).transpose(1, 2)
            rows = alpha.flatten(2).transpose(1, 2)  # (B, R, L)
            slope = rows @ w1[..., 2 * k]  # (B, R, out): the position term's weights, mixed
            later = rows @ later  # (B, R, 110): each row's own weights, mixed once
        else:
            fixed = term_i[:, :, None, 0] + term_j[:, None, :, 0]
            slope = w1[..., 2 * k]  # (B, 1, out)
        x = tanh(fixed.flatten(1, 2)[:, :, None] + rel[:, None] * slope[:, :, None])
        r, p = x.shape[1:3]
        if not self.attention_on:  # one set per instruction: the rows' positions are one bmm's
            x = x.reshape(b, 1, r * p, -1)
        shapes = self.layer_shapes[1:]
        parts = later.split([n_out * n_in for n_out, n_in in shapes], -1)
        for n, (w, (n_out, n_in)) in enumerate(zip(parts, shapes)):
            if n < len(shapes) - 1:
                x = tanh(x @ w.unflatten(-1, (n_in, n_out)))
            else:  # the output (one unit): a product and a sum, not a matmul of one column
                x = (x * w.unsqueeze(-2)).sum(-1)
        return x.view(b, r, p), rows if self.attention_on else None

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
        once for all its offsets, so the table wins on any map but the smallest.
        """
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
        radius = self.cfg.radius
        phi = self.phi(grids)  # (B, H+2, W+2, k)
        phi_i = phi[:, radius:radius + h, radius:radius + w].flatten(1, 2)  # (B, N, k)
        phi_j = torch.stack(shifted(phi, radius), dim=3).flatten(1, 2)  # (B, N, 8, k)
        text = self.text(tokens)
        r, attention = self.relations(phi_i, phi_j, text)  # (B, N, 8)
        z1 = r.max(dim=-1).values.view(b, h, w)
        far = None
        if self.cfg.far:  # its score has no offset term: a table over the kinds present
            kinds = present_kinds(grids, self.cfg.n_entities)
            far = self.far_map(grids, kinds, self.far_table(text, kinds))
        values = self.head(z1, self.decoder(text[2])[:, -self.head.code_size:], far)  # h's last
        # how much each word mattered, averaged over all pairs
        word_attention = None if attention is None else attention.mean(dim=(1, 2))
        return outputs(values, z1, word_attention, return_aux)

    def text_code(self, tokens: torch.Tensor, kinds: torch.Tensor | None = None) -> dict:
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
        return {
            'kinds': kinds,
            'relations': r[..., :n_nbrs],
            'attention': attention,
            'head': self.decoder(text[2])[:, -self.head.code_size:],
            'far': far,
        }

    def kind_rows(self, grids: torch.Tensor, kinds: torch.Tensor) -> torch.Tensor:
        """
        Return each cell's row in a table over `kinds`, (B, H*W); a kind it lacks: an error.

        `kinds` (K,): one table for every map; (B, K): one per map.
        """
        kinds = kinds.expand(len(grids), -1)  # a shared table: the same kinds for every map
        row = torch.full((len(grids), self.phi.embed.num_embeddings), -1, device=grids.device)
        row.scatter_(1, kinds, torch.arange(kinds.shape[1], device=grids.device).expand_as(kinds))
        cells = row.gather(1, grids.flatten(1))
        if cells.min() < 0:
            missing = sorted(set(grids.flatten(1)[cells < 0].tolist()))
            raise ValueError(f'the relation table lacks entity kinds {missing} of the grid')
        return cells

    def far_table(self, text: tuple, kinds: torch.Tensor) -> torch.Tensor:
        """Score each (kind_i, kind_j) of `kinds` with the far relation: (B, K, K)."""
        r, _ = self.table(kinds, kinds, text, torch.tensor([FAR_POSITION], device=kinds.device))
        return r.view(-1, kinds.shape[-1], kinds.shape[-1])

    def far_map(
        self,
        grids: torch.Tensor,
        kinds: torch.Tensor,
        table: torch.Tensor,
        rows: torch.Tensor | None = None,
    ):
        """
        Return the far relation map (B, H, W): per cell i, max over j of far - cost d^2.

        j runs over the cells within FAR_REACH rows and columns of i, d = |i - j|, and far is
        the far relation's score of (kind_i, kind_j), from `table`. A few maps no larger than
        the reach take that definition as it stands: every cell pair, one gather (FAR_PAIRS).
        Otherwise a cell's own kind a is at distance 0, so far(a, a) is its floor, and a kind k can
        raise it only where far(a, k) - cost * d^2 > far(a, a): only such kinds are measured,
        and only as far as that gain reaches (exact, and a fraction of the work on a large
        map). Per kind k, each cell adds its row's far(a, k) to -cost times its squared
        distance to the nearest k. `rows`: the cells' kind_rows, when the caller has them.
        """
        b, h, w = grids.shape
        if rows is None:
            rows = self.kind_rows(grids, kinds)  # (B, H*W): each cell's row of the table
        table = table.expand(b, -1, -1)
        cost = self.far_log_cost.exp()
        n = kinds.shape[-1]
        if h <= FAR_REACH + 1 and w <= FAR_REACH + 1 and b * (h * w) ** 2 <= FAR_PAIRS:
            pairs = (rows[:, :, None] * n + rows[:, None, :]).flatten(1)  # (B, N * N)
            scores = table.flatten(1).gather(1, pairs).view(b, h * w, h * w)
            return (scores - cost * pair_distances(h, w, grids.device)).amax(-1).view(b, h, w)
        out = table.diagonal(dim1=1, dim2=2).gather(1, rows).view(b, h, w)  # far(a, a)
        present = torch.bincount(rows.flatten(), minlength=n) > 0
        gain = (table - table.diagonal(dim1=1, dim2=2)[..., None])[:, present]  # (B, A, K)
        gain = gain.detach().amax(dim=(0, 1))  # per kind k, over the kinds a present
        useful = ((gain > 0) & present).nonzero().flatten()
        if not len(useful):
            return out
        top = gain[useful].max()
        reach = min(int(torch.sqrt(top / cost.detach())), FAR_REACH)
        # a cell with no k within reach scores at most floor + gain - cost * FAR_BEYOND: below
        # its floor unless the gain is that large, so only then must it be masked out
        masked = bool(top >= cost.detach() * FAR_BEYOND)
        # each cell's far(a, k) for the useful kinds k: one lookup in the B * K rows of the
        # tables, (U, B, H, W)
        lookup = table[:, :, useful].permute(2, 0, 1).reshape(len(useful), b * n)
        cells = (rows + torch.arange(b, device=grids.device)[:, None] * n).flatten()
        scores = lookup.index_select(1, cells).view(len(useful), b, h, w)
        chunk = max(1, FAR_CHUNK_CELLS // (b * h * w))
        for start in range(0, len(useful), chunk):
            ks = kinds[..., useful[start:start + chunk]].expand(b, -1)  # (B, U): each map's
            with torch.no_grad():
                dist = squared_distances(grids[:, None] == ks[:, :, None, None], reach)
            near = scores[start:start + chunk].transpose(0, 1).addcmul(dist, -cost)
            if masked:
                near = near.masked_fill(dist >= FAR_BEYOND, float('-inf'))
            out = torch.maximum(out, near.amax(1))  # over the chunk's kinds, per map
        return out

    def ground(self, grids: torch.Tensor, code: dict, return_aux: bool = False):
        """Value maps of grids (B, H, W) for a text_code of B instructions (or of 1 for all)."""
        b, h, w = grids.shape
        kinds, relations = code['kinds'], code['relations']  # (B or 1, Ki * Kj, P)
        n_rows, p = relations.shape[1:]
        radius = self.cfg.radius
        # each pair's (kind_i, kind_j) row, i * Kj + j, with j the off-map row past the border
        n_kinds = kinds.shape[-1]
        centre = self.kind_rows(grids, kinds)  # (B, N)
        around = F.pad(centre.view(b, h, w), (radius,) * 4, value=n_kinds)
        neighbours = torch.stack(shifted(around, radius), -1).view(b, h * w, p)
        pairs = centre[..., None] * (n_kinds + 1) + neighbours  # (B, N, P)
        # one gather from the flattened table: the pair's row * P + its offset
        index = (pairs * p + torch.arange(p, device=grids.device)).view(b, -1)
        r = relations.flatten(1).expand(b, -1).gather(1, index)
        z1 = r.view(b, h * w, p).amax(-1).view(b, h, w)
        far = None if code['far'] is None else self.far_map(grids, kinds, code['far'], centre)
        values = self.head(z1, code['head'].expand(b, -1), far)
        word_attention = None
        if return_aux and code['attention'] is not None:
            # the mean over the map's pairs: each kind pair's attention times its pair count
            if b > 1:
                pairs = pairs + torch.arange(b, device=grids.device)[:, None, None] * n_rows
            counts = torch.bincount(pairs.flatten(), minlength=b * n_rows).to(relations.dtype)
            word_attention = (counts.view(b, 1, n_rows) @ code['attention'].expand(b, -1, -1))[
                :, 0
            ] / (p * h * w)
        return outputs(values, z1, word_attention, return_aux)
