# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
A tiny training on generated worlds, for test_distributed.py.

test_distributed.py calls run() in its own process and starts this file under torchrun, which
runs it in each process: `python distributed_entry.py OUT MODEL` trains MODEL into OUT (rank 0
writes the checkpoint) and writes OUT/rows<rank>.json, the rows of each training forward of that
process.
"""

import json
from pathlib import Path
import sys

from spatial_grounding_ros.data.generator import generate
from spatial_grounding_ros.models.baselines import TCNN
from spatial_grounding_ros.models.trnet import TRNet
from spatial_grounding_ros.training.supervised import train_supervised, TrainConfig
import torch

# 3 epochs; t-RNetAttn's attention is off for the first: its weights get no gradient, then do.
# Batches of 15 split 8 + 7 over 2 processes, and 51 generated worlds leave 46 to train on
# (5 held out for validation): each epoch has a batch of 1, which leaves a process none.
# The goal cross-entropy's temperature is learned: a tensor outside the model DDP wraps.
CONFIG = TrainConfig(
    epochs=3,
    batch_size=15,
    lr=3e-3,
    attention_warmup=1 / 3,
    synthetic=0,
    mirrors=False,
    world_instructions=False,
    goal_weight=1.0,
    learn_goal_scale=True,
    select='mse',
    seed=3,
    threads=1,
)
WORLDS = 51


def run(out: Path, model: str) -> tuple[Path, dict, list[int], dict]:
    """
    Train `model` with CONFIG into `out`.

    Returns the checkpoint's path, the summary, the rows of each training forward and the
    weights training started from.
    """
    rows, start = [], {}

    def count(module, args):
        if isinstance(module, (TRNet, TCNN)) and module.training:
            if not rows:
                start.update({k: v.clone() for k, v in module.state_dict().items()})
            rows.append(args[0].shape[0])

    hook = torch.nn.modules.module.register_module_forward_pre_hook(count)
    try:
        path, summary = train_supervised(
            'pw-local',
            model,
            '',
            out,
            CONFIG,
            train_data=generate(WORLDS, seed=5, mode='local'),
            progress=False,
        )
    finally:
        hook.remove()
    return path, summary, rows, start


if __name__ == '__main__':
    import os

    out = Path(sys.argv[1])
    _, _, rows, _ = run(out, sys.argv[2])
    out.mkdir(parents=True, exist_ok=True)
    (out / f'rows{os.environ["RANK"]}.json').write_text(json.dumps(rows))
