# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The optimisation of one supervised training run, epoch by epoch and step by step.

Batches of similar instruction length, the loss (value-map MSE plus the goal cell's
cross-entropy), the attention warm-up, the distractors and noise words drawn per batch, and
each process's share of a batch under torchrun (distributed.py).
"""

from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F

from . import distributed
from ..core.text import Vocabulary
from ..data.augment import (
    absent_name_pools,
    add_distractors,
    filler_word_ids,
    insert_noise_words,
)
from ..data.datasets import GroundingSet


def encode(vocab: Vocabulary, data: GroundingSet) -> tuple[torch.Tensor, torch.Tensor]:
    return torch.from_numpy(data.grids), torch.from_numpy(vocab.encode_batch(data.instructions))


def batches(lengths: np.ndarray, batch_size: int, rng: np.random.Generator) -> list[np.ndarray]:
    """
    Return shuffled batches of similar instruction length.

    Sorted by length within pools of 8 batches, so padding, which the per-pair attention
    pays for, stays short.
    """
    order = rng.permutation(len(lengths))
    pool = batch_size * 8
    out = []
    for i in range(0, len(order), pool):
        chunk = order[i:i + pool]
        chunk = chunk[np.argsort(lengths[chunk], kind='stable')]
        out += [chunk[j:j + batch_size] for j in range(0, len(chunk), batch_size)]
    return [out[i] for i in rng.permutation(len(out))]


def trim_padding(tokens: torch.Tensor) -> torch.Tensor:
    """Drop padding columns that no row of this batch uses."""
    used = int((tokens != 0).any(0).nonzero().max()) + 1 if (tokens != 0).any() else 1
    return tokens[:, :used]


def goal_loss(pred: torch.Tensor, goals: torch.Tensor, scale) -> torch.Tensor:
    """
    Cross-entropy of the goal cell over the map's cells, the values times `scale` as logits.

    MSE alone barely penalises a peak one cell off (neighbouring true values differ by 10%), so the
    argmax often lands beside the goal, or on the object named.
    """
    b, h, w = pred.shape
    return F.cross_entropy(pred.reshape(b, h * w) * scale, goals[:, 0] * w + goals[:, 1])


class Epochs:
    """
    The optimisation of one training run: its optimizer, schedule, batches and noise.

    `tc` is the run's TrainConfig, resolved (recipe.py: no field the run reads is None). Each
    process of a data-parallel run builds the same one (same seeds) and runs its share of
    every batch (distributed.py).
    """

    def __init__(
        self,
        model,
        parts: list[GroundingSet],
        vocab: Vocabulary,
        tc,
        processes: distributed.Group,
        late: tuple[int, int] | None = None,
    ):
        self.model, self.tc, self.processes = model, tc, processes
        # parts from index late[0] on train from epoch late[1] on (TrainConfig.late_row_col)
        self.late = late or (len(parts), 0)
        # log of the goal logits' temperature; learned, it lets the cross-entropy ask for the
        # right argmax without pulling the values away from the MSE's (not part of the model)
        self.goal_log_scale = torch.tensor(
            float(np.log(tc.goal_scale)), requires_grad=tc.learn_goal_scale
        )
        self.opt = torch.optim.Adam(
            [*model.parameters()] + ([self.goal_log_scale] if tc.learn_goal_scale else []),
            lr=tc.lr,
        )
        self.encoded = []
        for part in parts:
            grids, tokens = encode(vocab, part)
            self.encoded.append(
                (
                    grids,
                    tokens,
                    torch.from_numpy(part.values),
                    torch.from_numpy(part.goals),
                    (tokens != 0).sum(1).numpy(),
                )
            )
        # late parts too, in every epoch: the measured --late-row-col runs' schedule
        self.steps_per_epoch = sum(int(np.ceil(len(p) / tc.batch_size)) for p in parts)
        # attention starts uniform (its weights 0): until warmup, the attention-free forward
        self.warmup = (
            int(tc.epochs * tc.attention_warmup) if model.capabilities.relation_attention else 0
        )
        # the model itself in one process; the warm-up leaves the attention weights unused
        self.trained = distributed.wrap(model, processes, find_unused=bool(self.warmup))
        self.sched = self.schedule(self.warmup or tc.epochs)
        self.rng = np.random.default_rng(tc.seed)
        self.distractor_rng = np.random.default_rng([tc.seed, 1])  # the same in every process
        self.text_noise_rng = np.random.default_rng([tc.seed, 2])
        self.fillers = filler_word_ids(vocab)
        # each kind's name's word id (-1: not a word of the vocabulary), for noise_names
        self.name_ids = np.array([vocab.index.get(n, -1) for n in parts[0].entities.names])

    def schedule(self, epochs: int):
        """Return a cosine decay from the optimizer's learning rate over `epochs` epochs."""
        return torch.optim.lr_scheduler.CosineAnnealingLR(
            self.opt, T_max=epochs * self.steps_per_epoch, eta_min=self.tc.lr_final
        )

    def run(self, epoch: int) -> float:
        """Train epoch `epoch` (from 0); return its mean training loss over all processes."""
        self.model.train()
        if self.warmup:  # uniform attention (attn weights still 0) == t-RNet, much cheaper
            self.model.attention_on = epoch >= self.warmup
            if epoch == self.warmup:  # attention starts learning: a full schedule of its own
                for group in self.opt.param_groups:
                    group['lr'] = self.tc.lr
                self.sched = self.schedule(self.tc.epochs - self.warmup)
        first_late, late_epoch = self.late
        plan = [
            (p, idx)
            for p, (*_, lengths) in enumerate(self.encoded)
            for idx in batches(lengths, self.tc.batch_size, self.rng)
            if p < first_late or epoch >= late_epoch
        ]
        losses = [self.step(*plan[p]) for p in self.rng.permutation(len(plan))]
        return float(np.mean(distributed.batch_losses(losses, self.processes)))

    def step(self, part: int, idx: np.ndarray) -> float:
        """Take one optimizer step on batch `idx` of part `part`; return its weighted loss."""
        tc, processes = self.tc, self.processes
        grids, tokens, values, goals, _ = self.encoded[part]
        batch = torch.from_numpy(idx)
        batch_grids = grids[batch]
        if tc.distractors:  # drawn for the whole batch: every process draws the same
            batch_grids = add_distractors(
                self.model, batch_grids, goals[batch], tc.distractors, self.distractor_rng
            )
        batch_tokens = tokens[batch]
        # likewise; only once the attention learns, which can pass over a word: the warm-up's
        # uniform average over the words cannot, and noise there cost "closest"
        # (docs/robustness.md)
        if tc.text_noise and (not self.warmup or self.model.attention_on):
            pools = (
                absent_name_pools(batch_grids, batch_tokens, self.name_ids)
                if tc.noise_names else None
            )
            batch_tokens = insert_noise_words(
                batch_tokens,
                self.fillers,
                tc.text_noise,
                self.text_noise_rng,
                pools,
                unknown=not tc.skip_unknown,  # a model that skips <unk>: no <unk> noise
                share=tc.noise_share,
            )
        # this process's share (weight 1.0: the whole batch, alone)
        share, weight = distributed.shard(np.arange(len(idx)), processes)
        share = torch.from_numpy(share)
        idx = batch[share]
        pred = self.trained(batch_grids[share], trim_padding(batch_tokens[share]))
        loss = torch.mean((pred - values[idx]) ** 2)
        if tc.goal_weight:
            loss = loss + tc.goal_weight * goal_loss(pred, goals[idx], self.goal_log_scale.exp())
        self.opt.zero_grad()
        (loss * weight).backward()
        distributed.average_gradients([self.goal_log_scale], processes)
        self.opt.step()
        self.sched.step()
        return loss.item() * weight
