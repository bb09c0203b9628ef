# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Data-parallel training under torchrun gives one process's results, up to float order.

The same tiny training (distributed_entry.py) runs alone, in this process, and in 2 CPU
processes under `torchrun --standalone` (gloo on localhost); the checkpoints must agree.
"""

import json
import os
from pathlib import Path
import subprocess
import sys

import pytest
from spatial_grounding_ros import cli
from spatial_grounding_ros.models.checkpoints import load_checkpoint
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent))
import distributed_entry  # noqa: E402, I100

ENTRY = Path(distributed_entry.__file__)


def gloo_available() -> bool:
    import torch.distributed as dist

    return dist.is_available() and dist.is_gloo_available()


@pytest.mark.skipif(not gloo_available(), reason='this torch build has no torch.distributed gloo')
@pytest.mark.parametrize('model', ['t-rnet-attn', 't-cnn'])  # with and without a warm-up
def test_two_processes_train_the_same_weights_as_one(tmp_path, model):
    one_path, one_summary, one_rows, start = distributed_entry.run(tmp_path / 'one', model)

    env = {k: v for k, v in os.environ.items() if k not in ('RANK', 'WORLD_SIZE', 'LOCAL_RANK')}
    env['OMP_NUM_THREADS'] = '1'
    two = tmp_path / 'two'
    done = subprocess.run(
        [
            sys.executable, '-m', 'torch.distributed.run', '--standalone', '--nproc_per_node', '2',
            str(ENTRY), str(two), model,
        ],
        env=env, capture_output=True, text=True, timeout=600,  # a hang, not a slow shared machine
    )
    assert done.returncode == 0, done.stdout + done.stderr
    one = load_checkpoint(one_path)
    two_ckpt = torch.load(two / one_path.name, weights_only=True)
    two_header = two_ckpt['header']

    # the processes split every batch, the first taking the odd example, and a process
    # left without any (a batch of 1) runs one at weight 0
    rows = [json.loads((two / f'rows{rank}.json').read_text()) for rank in (0, 1)]
    assert rows[0] == [(b + 1) // 2 for b in one_rows]
    assert rows[1] == [max(1, b // 2) for b in one_rows]
    assert any(b % 2 for b in one_rows) and 1 in one_rows  # the cases the split handles

    # same weights to float order, and they moved well beyond that from where they started
    for name, value in one.model.state_dict().items():
        assert torch.allclose(two_ckpt['state_dict'][name], value, rtol=0, atol=1e-5), name
    moved = max((v - start[k]).abs().max().item() for k, v in one.model.state_dict().items())
    assert moved > 1e-2
    if model == 't-rnet-attn':  # the attention learned after the warm-up
        assert (start['attn.weight'] != one.model.state_dict()['attn.weight']).any()

    # the same losses, validation, kept epoch and learned goal temperature
    assert two_header['processes'] == 2 and 'processes' not in one.header
    assert two_header['best_epoch'] == one.header['best_epoch'] == one_summary['best_epoch']
    assert two_header['goal_scale'] == pytest.approx(one.header['goal_scale'], abs=1e-3)
    assert one.header['goal_scale'] != distributed_entry.CONFIG.goal_scale
    for a, b in zip(two_header['loss_history'], one.header['loss_history'], strict=True):
        assert a == pytest.approx(b, abs=2e-5)


def test_shapeworld_training_refuses_torchrun(monkeypatch, capsys):
    """Refuse shapeworld-train under torchrun: each copy would train and write the same file."""
    monkeypatch.setenv('WORLD_SIZE', '2')
    assert cli.main(['shapeworld-train', '--model', 't-vgg']) == 2
    assert 'not under torchrun' in capsys.readouterr().err
