# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The relation network f, in its two halves: per cell pair, and per (kind_i, kind_j) table.

r_ij = f([phi_i; phi_j; l_ij]), f an MLP whose weights the instruction decodes. The per-pair
half (pair_relations) is the definition: it scores every cell against each neighbour. The
per-kind half (kind_table) uses that a pair's score, attention included, depends only on the
two kinds, their offset and the instruction, so it scores each (kind_i, kind_j, offset) once.

Both take the model's weights explicitly and hold none: `decoded`, the decoder's output for
the words (B, L, P) or their mean (B, P); `query`, the attention projection of the words
(B, L, 2k), None without attention; `mask`, the words' padding mask (B, L); the entity table
`embed` (kinds, k); `layer_shapes`, the MLP's (out, in) per layer. models.trnet wires them.
"""

from __future__ import annotations

import torch

from .encoders import shifted


def sigmoid_tanh(x: torch.Tensor) -> torch.Tensor:
    """Return 2 sigmoid(2x) - 1, which is tanh(x) (see Tanh)."""
    return torch.sigmoid(x * 2).mul_(2).sub_(1)


class Tanh(torch.autograd.Function):
    """
    tanh, computed as 2 sigmoid(2x) - 1 (the same function).

    This torch's CPU tanh is several times slower than its sigmoid, and the relation MLP's tanh
    was a visible share of a training step and of a new instruction's text code
    (docs/benchmarks.md). The backward is tanh's own, from the output: grad * (1 - y^2).
    """

    @staticmethod
    def forward(ctx, x: torch.Tensor) -> torch.Tensor:
        y = sigmoid_tanh(x)
        ctx.save_for_backward(y)
        return y

    @staticmethod
    def backward(ctx, grad: torch.Tensor) -> torch.Tensor:
        (y,) = ctx.saved_tensors
        return torch.ops.aten.tanh_backward(grad, y)


def tanh(x: torch.Tensor) -> torch.Tensor:
    """Return the tanh of x as Tanh computes it, with no autograd call when none is needed."""
    return Tanh.apply(x) if x.requires_grad and torch.is_grad_enabled() else sigmoid_tanh(x)


def split_params(params: torch.Tensor, layer_shapes: list[tuple[int, int]]) -> list[torch.Tensor]:
    """
    Cut a parameter vector (..., P) into the relation MLP's weights (..., out, in) per layer.

    One split, not a slice per layer: a slice's backward fills a zero tensor of the vector's
    size, per layer. Entries past the layers (the head's code) are left out.
    """
    sizes = [out * inp for out, inp in layer_shapes]
    parts = params.split([*sizes, params.shape[-1] - sum(sizes)], -1)
    return [part.unflatten(-1, shape) for part, shape in zip(parts, layer_shapes)]


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
        # columns, (B, in, N * P), which torch runs faster than N * P rows of `in`
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


def cell_pairs(phi: torch.Tensor, radius: int) -> tuple[torch.Tensor, torch.Tensor]:
    """
    Return the centres phi_i (B, N, k) and their neighbours phi_j (B, N, P, k) of a map.

    `phi` (B, H+2r, W+2r, k) is the embedded map padded by `radius` with the off-map entity.
    """
    h, w = phi.shape[1] - 2 * radius, phi.shape[2] - 2 * radius
    phi_i = phi[:, radius:radius + h, radius:radius + w].flatten(1, 2)
    phi_j = torch.stack(shifted(phi, radius), dim=3).flatten(1, 2)
    return phi_i, phi_j


def pair_attention(
    phi_i: torch.Tensor, phi_j: torch.Tensor, query: torch.Tensor, mask: torch.Tensor
) -> torch.Tensor:
    """
    Return alpha_ij(k) ~ exp(h(k)^T A [phi_i; phi_j]) over words, (B, N, P, L).

    `query` is A h(k) for each word (B, L, 2k). The score splits into an i part and a j part,
    so it costs (B, N, L) + (B, N, P, L), not a product over all three.
    """
    k = phi_j.shape[-1]
    score = torch.einsum('bnd,bld->bnl', phi_i, query[..., :k]).unsqueeze(2) + torch.einsum(
        'bnpd,bld->bnpl', phi_j, query[..., k:]
    )
    score = score.masked_fill(~mask[:, None, None, :], float('-inf'))
    return score.softmax(-1)


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
    (2k+1)-wide weight, which takes a share of the relation MLP's work on a map (PuddleWorld:
    260 -> 180 multiply-adds a pair). With attention the words' terms are mixed by it, per
    pair.
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


def pair_relations(
    phi_i: torch.Tensor,
    phi_j: torch.Tensor,
    rel: torch.Tensor,
    decoded: torch.Tensor,
    layer_shapes: list[tuple[int, int]],
    query: torch.Tensor | None = None,
    mask: torch.Tensor | None = None,
) -> tuple[torch.Tensor, torch.Tensor | None]:
    """
    Score every pair of a map: centres phi_i (B, N, k) against phi_j (B, N, P, k).

    `rel` (P,): each offset's position code. With a `query` the weights are the words'
    (`decoded` (B, L, P)) mixed per pair by attention; without, one set per map (`decoded`
    (B, P), from the words' mean). Returns r (B, N, P) and the attention over words
    (B, N, P, L), or None.
    """
    # the decoder is linear and sum_k alpha = 1, so decoding h_ij = sum_k alpha_ij(k) h(k)
    # equals the alpha-weighted sum of the words' decoded parameters: relation_mlp mixes those
    attention = None if query is None else pair_attention(phi_i, phi_j, query, mask)
    weights = split_params(decoded, layer_shapes)  # (B, [L,] out, in) per layer
    first = first_layer(weights[0], phi_i, phi_j, rel, attention)
    return relation_mlp(weights[1:], tanh(first), attention), attention


def kind_table(
    embed: torch.Tensor,
    kinds: torch.Tensor,
    kinds_j: torch.Tensor,
    rel: torch.Tensor,
    decoded: torch.Tensor,
    layer_shapes: list[tuple[int, int]],
    query: torch.Tensor | None = None,
    mask: torch.Tensor | None = None,
) -> tuple[torch.Tensor, torch.Tensor | None]:
    """
    Score every (kind_i, kind_j) of `kinds` x `kinds_j` at each position code of `rel` (P,).

    `kinds` and `kinds_j` are (K,), one table for every instruction, or (B, K), one each.
    `decoded` (B, L, P): each word's parameters, mixed by attention when a `query` is given;
    t-RNet is the same computation with one 'word', the LSTM outputs' mean, at weight 1.
    Returns r (B, Ki * Kj, P), row i * Kj + j, and the attention over words of each row
    (B, Ki * Kj, L), or None without attention. A pair's attention has no position term,
    so a row mixes the words' weights once for all its positions, where a map's pairs
    would each mix their own. The first layer splits into an i, a j and a position term
    (first_layer), here computed per kind and per word before the mix.
    """
    b, k = len(decoded), embed.shape[1]
    # (B, Ki, k), (B, Kj, k)
    phi_i, phi_j = (embed[kinds].expand(b, -1, -1) for kinds in (kinds, kinds_j))
    # each word's relation MLP, (B, L, out, in) per layer
    w1, *later_layers = split_params(decoded, layer_shapes)
    n_words, out = w1.shape[1:3]
    # each kind's i and j terms for every word: (B, Ki, L, out), (B, Kj, L, out)
    term_i = (phi_i @ w1[..., :k].flatten(1, 2).mT).unflatten(-1, (n_words, out))
    term_j = (phi_j @ w1[..., k:2 * k].flatten(1, 2).mT).unflatten(-1, (n_words, out))
    # the later layers' weights side by side, each as (in, out): x @ w, no transpose
    later = torch.cat([w.mT.flatten(-2) for w in later_layers], -1)  # (B, L, 110)
    rows = None
    if query is not None:
        # alpha ~ exp(h^T A [phi_i; phi_j]): an i part and a j part, (B, L, Ki, Kj). The
        # softmax runs over dim 1, where this torch's CPU softmax is much faster than over a
        # short last dimension (docs/benchmarks.md)
        score = (query[..., :k] @ phi_i.mT)[..., :, None] + (query[..., k:] @ phi_j.mT)[
            ..., None, :
        ]
        alpha = score.masked_fill(~mask[:, :, None, None], float('-inf')).softmax(1)
        # the terms mixed per (kind_i, kind_j): (B, Ki, Kj, out)
        # (the j side's permuted alpha made contiguous first: the same products, but a
        # strided batch sends the matmul down a per-batch copy path four times slower)
        fixed = alpha.permute(0, 2, 3, 1) @ term_i + (
            alpha.permute(0, 3, 2, 1).contiguous() @ term_j
        ).transpose(1, 2)
        rows = alpha.flatten(2).transpose(1, 2)  # (B, R, L)
        slope = rows @ w1[..., 2 * k]  # (B, R, out): the position term's weights, mixed
        later = rows @ later  # (B, R, 110): each row's own weights, mixed once
    else:
        fixed = term_i[:, :, None, 0] + term_j[:, None, :, 0]
        slope = w1[..., 2 * k]  # (B, 1, out)
    x = tanh(fixed.flatten(1, 2)[:, :, None] + rel[:, None] * slope[:, :, None])
    r, p = x.shape[1:3]
    if query is None:  # one set per instruction: the rows' positions are one bmm's
        x = x.reshape(b, 1, r * p, -1)
    shapes = layer_shapes[1:]
    parts = later.split([n_out * n_in for n_out, n_in in shapes], -1)
    for n, (w, (n_out, n_in)) in enumerate(zip(parts, shapes)):
        if n < len(shapes) - 1:
            x = tanh(x @ w.unflatten(-1, (n_in, n_out)))
        else:  # the output (one unit): a product and a sum, not a matmul of one column
            x = (x * w.unsqueeze(-2)).sum(-1)
    return x.view(b, r, p), rows
