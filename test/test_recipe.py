# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
A run in one place: `recipe(task, model)` and `train --show-config`.

The recipe resolves every TrainConfig and ModelConfig field of a run from the task, the model's
own fields and the settings every task shares (core/tasks.py); the shipped checkpoints were
trained with what it gives, and `train --show-config` prints it for every task and model.
"""

from dataclasses import fields
import json
import subprocess
import sys

import pytest
from spatial_grounding_ros.cli import main
from spatial_grounding_ros.core import tasks
from spatial_grounding_ros.models.checkpoints import load_checkpoint, PACKAGED_DIR
from spatial_grounding_ros.models.config import ModelConfig
from spatial_grounding_ros.models.registry import MODELS
from spatial_grounding_ros.training.recipe import FROM_DATA, recipe, TrainConfig

RUNS = [(t, m) for t in tasks.TASKS for m in MODELS]
# fields a shipped checkpoint's header holds that are no setting of the recipe: `make
# reproduce` trains on one thread; headers written before the recipe resolved them hold None
# for "the default" (LATE_FROM, NOISE_SHARE, off)
NOT_RECIPE = {'threads'}
OFF = {'late_from': tasks.LATE_FROM, 'noise_share': tasks.NOISE_SHARE, 'noise_names': False,
       'skip_unknown': False, 'skip_absent_names': False, 'late_row_col': 0}


@pytest.mark.parametrize('task,model', RUNS)
def test_the_recipe_sets_every_field(task, model):
    run = recipe(task, model)
    unset = {f.name for f in fields(TrainConfig) if getattr(run.train, f.name) is None}
    # no checkpoint to start from; ISI generates no worlds
    assert unset == ({'init', 'generator_mode'} if task == 'isi' else {'init'})
    assert run.train.late_from == tasks.LATE_FROM
    assert run.synthetic_sizes == tasks.SYNTHETIC_SIZES
    unset = {f.name for f in fields(ModelConfig) if getattr(run.model_config, f.name) is None}
    assert unset == {'vocab_size'}  # the run's data counts it


SHIPPED = sorted(
    p.stem for p in PACKAGED_DIR.glob('*.pt') if p.stem.split('_')[0] in tasks.TASKS
)


@pytest.mark.parametrize('name', SHIPPED)
def test_the_shipped_checkpoints_were_trained_with_their_recipe(name):
    """Each shipped checkpoint's header holds the recipe's values of its task and model."""
    loaded = load_checkpoint(name)
    run = recipe(loaded.header['task'], loaded.name)
    recorded = loaded.header['train_config']
    assert recorded, name
    for key, value in recorded.items():
        if key not in NOT_RECIPE:
            assert getattr(run.train, key) == (OFF.get(key) if value is None else value), key
    trained = loaded.model.cfg.to_dict()
    for key, value in run.model_config.to_dict().items():
        if key not in FROM_DATA:
            assert trained[key] == value, key


def test_given_options_win_over_the_tasks():
    run = recipe('pw', 't-rnet-attn', TrainConfig(epochs=3, noise_share=0.2, paper_model=True))
    assert (run.train.epochs, run.train.noise_share) == (3, 0.2)
    assert run.train.late_row_col == tasks.TASKS['pw'].recipes['t-rnet-attn']['late_row_col']
    cfg = run.model_config
    assert (cfg.axial, cfg.far, cfg.head_text) == (False, False, False)  # the paper's model
    assert recipe('pw', 't-rnet', radius=2).model_config.radius == 2


@pytest.mark.parametrize(
    'task,model,tc,needle',
    [
        ('isi', 't-rnet', TrainConfig(synthetic=10), 'task isi is not PuddleWorld'),
        ('pw', 't-uvfa', TrainConfig(distractors=2), 't-uvfa has no distractor kinds'),
        ('pw', 't-cnn', TrainConfig(skip_absent_names=True), 't-cnn does not read it'),
    ],
)
def test_the_recipe_refuses_what_the_run_refuses(task, model, tc, needle):
    with pytest.raises(ValueError, match=needle):
        recipe(task, model, tc)


@pytest.mark.parametrize('task,model', RUNS)
def test_show_config_prints_the_recipe_for_every_task_and_model(task, model, capsys):
    argv = ['train', '--task', task, '--model', model, '--data', '/nonexistent', '--show-config']
    assert main(argv) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith(f'# {task} {model}')
    names = [line.split(' = ')[0] for line in lines if ' = ' in line]
    assert names == [
        *(f.name for f in fields(TrainConfig)), *(f.name for f in fields(ModelConfig)),
        'synthetic_sizes',
    ]
    assert [line for line in lines if line.startswith('[')] == ['[train]', '[model]', '[data]']
    run = recipe(task, model)
    assert f'epochs = {run.train.epochs}' in lines
    assert main([*argv, '--json']) == 0
    assert json.loads(capsys.readouterr().out) == run.to_dict()


def test_show_config_from_the_command_line():
    """Options given show over the task's; nothing is trained, no data read; bad ones: exit 2."""
    base = [sys.executable, '-m', 'spatial_grounding_ros.cli', 'train', '--task', 'pw-local',
            '--model', 't-cnn', '--data', '/nonexistent', '--show-config']
    shown = subprocess.run([*base, '--epochs', '3'], capture_output=True, text=True, timeout=120)
    assert shown.returncode == 0, shown.stderr
    assert 'epochs = 3' in shown.stdout.splitlines()
    refused = subprocess.run(
        [*base, '--skip-absent-names'], capture_output=True, text=True, timeout=120
    )
    assert refused.returncode == 2
    assert refused.stderr.strip() == (
        'spatial-grounding: error: --skip-absent-names: t-cnn does not read it (t-RNet models do)'
    )
