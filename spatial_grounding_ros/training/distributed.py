# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Data-parallel training under torchrun: the process group and each process's share of a batch.

`torchrun --nproc_per_node N spatial-grounding train ...` starts N copies of the command with
RANK, WORLD_SIZE, MASTER_ADDR and MASTER_PORT set. Each copy builds the same data, model and
batch plan (same seed), runs its shard of every batch, and DDP averages the gradients: every step
is one process's step on the whole batch, up to the order of floating-point sums. Without
WORLD_SIZE (or with 1) every function here is a no-op and training runs the one-process code.
"""

from __future__ import annotations

from dataclasses import dataclass
import os

import numpy as np
import torch


@dataclass(frozen=True)
class Group:
    """This process's place among the training processes; the default: one process."""

    rank: int = 0
    size: int = 1
    owned: bool = False  # start() created the process group, so finish() ends it

    @property
    def main(self) -> bool:
        """Say whether this is the process that prints progress and writes the checkpoint."""
        return self.rank == 0


def world_size() -> int:
    """Return the number of processes torchrun started (1 without torchrun)."""
    return int(os.environ.get('WORLD_SIZE', 1))


def is_main_process() -> bool:
    """Say whether this is rank 0 or there is no torchrun: the one process that reports."""
    return int(os.environ.get('RANK', 0)) == 0


def backend() -> str:
    """Return gloo for CPU tensors (training runs on the CPU), NCCL for CUDA tensors if any."""
    return 'cpu:gloo,cuda:nccl' if torch.cuda.is_available() else 'gloo'


def start() -> Group:
    """Join torchrun's process group (created here unless the caller did), or run alone."""
    if world_size() == 1:
        return Group()
    import torch.distributed as dist

    if not dist.is_available():
        raise ValueError('this torch build has no torch.distributed: run one process')
    owned = not dist.is_initialized()
    if owned:
        dist.init_process_group(backend())
    return Group(dist.get_rank(), dist.get_world_size(), owned)


def wrap(model: torch.nn.Module, group: Group, find_unused: bool) -> torch.nn.Module:
    """
    Return the module to train through: DDP over the processes, or the model itself alone.

    find_unused: some steps leave parameters without a gradient (t-RNetAttn's attention weights
    during the warm-up). DDP then leaves their .grad unset on every process, as one process does,
    so Adam skips them (its step count for them starts with the attention, as alone). Otherwise
    off: every model uses all its parameters in every forward, and the search costs a pass over
    the autograd graph each step.
    """
    if group.size == 1:
        return model
    from torch.nn.parallel import DistributedDataParallel

    return DistributedDataParallel(model, find_unused_parameters=find_unused)


def shard(idx: np.ndarray, group: Group) -> tuple[np.ndarray, float]:
    """
    Return this process's share of a batch and the weight of its mean loss.

    Shares differ by at most one example. DDP averages the processes' gradients, so the mean loss
    of a share of n of the batch's B examples is weighted N * n / B: the average is then the
    gradient of the whole batch's mean loss, whether or not N divides B. A batch of fewer than N
    examples leaves a process without any: it runs the first example at weight 0, since every
    process has to take part in each step's gradient all-reduce.
    """
    if group.size == 1:
        return idx, 1.0
    share = np.array_split(idx, group.size)[group.rank]
    if not len(share):
        return idx[:1], 0.0
    return share, group.size * len(share) / len(idx)


def average_gradients(tensors: list[torch.Tensor], group: Group) -> None:
    """Average over the processes the gradients of tensors outside the model DDP wraps."""
    if group.size == 1:
        return
    import torch.distributed as dist

    for tensor in tensors:
        if tensor.grad is not None:
            dist.all_reduce(tensor.grad)
            tensor.grad /= group.size


def batch_losses(weighted: list[float], group: Group) -> list[float]:
    """
    Each step's loss over the whole batch, from every process's weighted share loss.

    `weighted` holds this process's loss times its shard() weight, per step; their sum over the
    processes, divided by N, is the batch's mean loss.
    """
    if group.size == 1:
        return weighted
    import torch.distributed as dist

    total = torch.tensor(weighted, dtype=torch.float64)
    dist.all_reduce(total)
    return (total / group.size).tolist()


def finish(group: Group) -> None:
    """Wait until every process is done (the checkpoint is written), then end the group."""
    if group.size == 1:
        return
    import torch.distributed as dist

    dist.barrier()
    if group.owned:
        dist.destroy_process_group()
