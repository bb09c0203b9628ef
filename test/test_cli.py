# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""The command line: JSON output, determinism, and one-line errors with exit status 2."""

import json
import subprocess
import sys

import pytest
from spatial_grounding_ros.models.checkpoints import PACKAGED_DIR
import torch


def run(*args, timeout=300):
    return subprocess.run(
        [sys.executable, '-m', 'spatial_grounding_ros.cli', *args],
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def assert_one_line_error(result, *needles):
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert 'Traceback' not in result.stderr
    for needle in needles:
        assert needle in lines[0]


def test_eval_prints_exactly_one_json_object(data_dir):
    r = run(
        'eval',
        '--checkpoint',
        str(PACKAGED_DIR / 'pw-local_t-rnet-attn.pt'),
        '--task',
        'pw-local',
        '--split',
        'test',
        '--data',
        str(data_dir),
        '--json',
    )
    assert r.returncode == 0, r.stderr
    metrics = json.loads(r.stdout)
    assert set(metrics) >= {'mse', 'pq', 'md', 'n'} and metrics['n'] == 399


def test_train_is_deterministic_with_seed(data_dir, tmp_path):
    for out in ('a', 'b'):
        r = run(
            'train',
            '--task',
            'pw-local',
            '--model',
            't-cnn',
            '--epochs',
            '2',
            '--seed',
            '3',
            '--synthetic',
            '300',
            '--data',
            str(data_dir),
            '--out',
            str(tmp_path / out),
            '--threads',
            '1',
        )
        assert r.returncode == 0, r.stderr
    a = torch.load(tmp_path / 'a' / 'pw-local_t-cnn.pt', weights_only=True)
    b = torch.load(tmp_path / 'b' / 'pw-local_t-cnn.pt', weights_only=True)
    assert a['header']['val_metrics'] == b['header']['val_metrics']
    for key in a['state_dict']:
        torch.testing.assert_close(a['state_dict'][key], b['state_dict'][key], rtol=0, atol=0)


def test_missing_data_is_one_line(tmp_path):
    r = run('train', '--task', 'pw-local', '--model', 't-cnn', '--data', str(tmp_path))
    assert_one_line_error(r, 'local.p', 'not found')


def test_unknown_names_are_one_line():
    assert_one_line_error(run('train', '--task', 'pw-mars', '--model', 't-cnn'), 'pw-mars')
    assert_one_line_error(run('train', '--task', 'pw-local', '--model', 'resnet'), 'resnet')


def test_corrupt_and_foreign_checkpoints_are_one_line(tmp_path, data_dir):
    bad = tmp_path / 'bad.pt'
    bad.write_bytes(b'\x00garbage')
    assert_one_line_error(
        run('eval', '--checkpoint', str(bad), '--task', 'pw-local', '--data', str(data_dir)),
        'bad.pt',
        'not a readable checkpoint',
    )
    isi = PACKAGED_DIR / 'isi_t-cnn.pt'
    if not isi.is_file():
        pytest.skip('no packaged ISI checkpoint')
    assert_one_line_error(
        run('eval', '--checkpoint', str(isi), '--task', 'pw-local', '--data', str(data_dir)),
        'isi_t-cnn.pt',
        'entity table',
    )


@pytest.mark.parametrize(
    'option, value, needle',
    [
        ('--episodes', '-3', 'argument --episodes: must be at least 0, got -3'),
        ('--envs', '0', 'argument --envs: must be at least 1, got 0'),
        ('--gamma', '1.5', 'argument --gamma: must be 0..1, got 1.5'),
        ('--batch-maps', 'many', "argument --batch-maps: invalid int value: 'many'"),
    ],
)
def test_rl_train_refuses_an_option_out_of_its_range(option, value, needle):
    """Each range is declared once, in RLConfig: the command refuses before any work."""
    r = run('rl-train', '--task', 'generator-local', '--model', 't-cnn', option, value)
    assert_one_line_error(r, needle)


@pytest.mark.parametrize(
    'argv, needle',
    [
        (['--epochs', '-3'], 'argument --epochs: must be at least 1, got -3'),
        (['--epochs', '0'], 'argument --epochs: must be at least 1, got 0'),
        (['--batch-size', '0'], 'argument --batch-size: must be at least 1, got 0'),
        (['--synthetic', '-5'], 'argument --synthetic: must be at least 0, got -5'),
        (['--attention-warmup', '1.5'], 'argument --attention-warmup: must be 0..1, got 1.5'),
        (['--threads', '0'], 'argument --threads: must be at least 1, got 0'),
        (['--lr', 'fast'], "argument --lr: invalid float value: 'fast'"),
        (['--select', 'hit'], "argument --select: invalid choice: 'hit'"),
    ],
)
def test_train_refuses_an_option_out_of_its_range(argv, needle, tmp_path):
    """
    Each range is declared once, in TrainConfig: the command refuses before any work.

    The data folder is empty, so a command that went on would fail on the data instead, with
    another message.
    """
    r = run('train', '--task', 'pw-local', '--model', 't-cnn', '--data', str(tmp_path), *argv)
    assert_one_line_error(r, needle)
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize(
    'argv, needle',
    [
        (['reproduce', '--jobs', '0'], 'argument --jobs: must be at least 1, got 0'),
        (['reproduce', '--tasks', 'pw-mars'], "argument --tasks: invalid choice: 'pw-mars'"),
        (['reproduce-rl', '--jobs', '0'], 'argument --jobs: must be at least 1, got 0'),
        (['reproduce-rl', '--episodes-scale', '-1'], 'argument --episodes-scale: must be'),
        (['suite', '--n', '0'], 'argument --n: must be at least 1, got 0'),
        (['demo', '--episodes', '0'], 'argument --episodes: must be at least 1, got 0'),
    ],
)
def test_other_commands_refuse_a_count_out_of_its_range(argv, needle):
    from spatial_grounding_ros.cli import build_parser

    with pytest.raises(SystemExit) as stop:
        build_parser().parse_args(argv)
    assert stop.value.code == 2
    r = run(*argv)
    assert_one_line_error(r, needle)


def test_train_options_are_the_config_fields():
    """`train` has one option per TrainConfig field; options not given leave the defaults."""
    from dataclasses import fields

    from spatial_grounding_ros.cli import build_parser
    from spatial_grounding_ros.core.tasks import TASKS
    from spatial_grounding_ros.training.options import given_options
    from spatial_grounding_ros.training.supervised import TrainConfig

    base = ['train', '--task', 'pw', '--model', 't-cnn']
    args = build_parser().parse_args(base)
    assert given_options(TrainConfig, args) == {}
    assert TrainConfig().for_task('pw', 't-rnet-attn') == TrainConfig(
        epochs=TASKS['pw'].epochs,
        synthetic=TASKS['pw'].synthetic,
        world_instructions=True,
        mirrors=True,
        attention_warmup=TASKS['pw'].attention_warmup,
        goal_weight=TASKS['pw'].goal_weight,
        distractors=TASKS['pw'].distractors,
        text_noise=TASKS['pw'].text_noise,
        paraphrase=TASKS['pw'].paraphrase,
        generator_mode=TASKS['pw'].generator_mode,
        late_from=TASKS['pw'].late_from,
        select=TASKS['pw'].select,
        **TASKS['pw'].recipes['t-rnet-attn'],  # the default's own fields (late row-col worlds)
    )
    # every field is set but the checkpoint to start from (the run resolved: recipe.py)
    assert [f.name for f in fields(TrainConfig) if getattr(
        TrainConfig().for_task('pw-local', 't-cnn'), f.name) is None] == ['init']
    # the paper's baselines have a recipe of their own: MSE alone, no distractor objects
    baseline = TrainConfig().for_task('pw-local', 't-cnn')
    assert (baseline.goal_weight, baseline.distractors) == (0.0, 0)
    assert baseline.epochs == TASKS['pw-local'].recipes['t-cnn']['epochs'] == 70
    args = build_parser().parse_args(
        base + ['--no-mirrors', '--epochs', '7', '--batch-size', '8', '--select', 'mse']
    )
    given = given_options(TrainConfig, args)
    assert given == {'mirrors': False, 'epochs': 7, 'batch_size': 8, 'select': 'mse'}
    # a value given wins over the task's
    assert TrainConfig(**given).for_task('pw', 't-cnn').epochs == 7
    args = build_parser().parse_args(base + ['--generator-mode', 'training-row-col'])
    mixed = TrainConfig(**given_options(TrainConfig, args)).for_task('pw', 't-cnn')
    assert mixed.generator_mode == 'training-row-col'
    assert all(f.metadata['help'] for f in fields(TrainConfig))
    with pytest.raises(ValueError, match='batch_size must be at least 1, got 0'):
        TrainConfig(batch_size=0)


@pytest.mark.parametrize(
    'option', [['--synthetic', '10'], ['--generator-mode', 'training'], ['--late-row-col', '10']]
)
def test_generated_worlds_are_refused_on_a_task_that_is_not_puddleworld(option):
    r = run('train', '--task', 'isi', '--model', 't-rnet', '--epochs', '1', *option)
    assert_one_line_error(
        r, '--synthetic, --generator-mode and --late-row-col add generated PuddleWorld worlds; '
        'task isi is not PuddleWorld'
    )


def test_shapeworld_train_refuses_the_grid_options():
    r = run('shapeworld-train', '--model', 't-vgg', '--synthetic', '10')
    assert_one_line_error(r, 'unrecognized arguments: --synthetic 10')
    # ShapeWorld has its own subcommands: the grid commands do not know the task
    r = run('train', '--task', 'shapeworld', '--model', 't-vgg')
    assert_one_line_error(r, "argument --task: invalid choice: 'shapeworld'")


def test_shapeworld_options_are_the_config_fields():
    """`shapeworld-train` has one option per ShapeWorld TrainConfig field, its default and help."""
    from dataclasses import fields

    from spatial_grounding_ros.cli import build_parser
    from spatial_grounding_ros.shapeworld.training import TrainConfig
    from spatial_grounding_ros.training.options import from_options

    base = ['shapeworld-train', '--model', 't-rnet-attn']
    parsed = vars(build_parser().parse_args(base))
    assert {f.name for f in fields(TrainConfig)} <= set(parsed), 'every field is an option'
    assert from_options(TrainConfig, build_parser().parse_args(base)) == TrainConfig()
    args = build_parser().parse_args(
        base + ['--warmup-size', '500', '--max-minutes', '1.5', '--no-mirror', '--epochs', '2']
    )
    assert from_options(TrainConfig, args) == TrainConfig(
        warmup_size=500, max_minutes=1.5, mirror=False, epochs=2
    )
    assert from_options(TrainConfig, build_parser().parse_args(
        base + ['--max-minutes', '0', '--warmup-size', '0']
    )) == TrainConfig(max_minutes=0.0, warmup_size=0)  # no time limit, no warm-up
    assert all(f.metadata['help'] for f in fields(TrainConfig))
    with pytest.raises(ValueError, match='warmup_absent must be 0..1, got 2'):
        TrainConfig(warmup_absent=2)


@pytest.mark.parametrize(
    'option, value, needle',
    [
        ('--warmup-size', '-1', 'argument --warmup-size: must be at least 0, got -1'),
        ('--max-minutes', '-5', 'argument --max-minutes: must be at least 0, got -5'),
        ('--max-minutes', 'soon', "argument --max-minutes: invalid float value: 'soon'"),
        ('--val-fraction', '1', 'argument --val-fraction: must be 0.01..0.9, got 1.0'),
    ],
)
def test_shapeworld_train_refuses_an_option_out_of_its_range(option, value, needle):
    """Each range is declared once, in ShapeWorld's TrainConfig: refused before any work."""
    r = run('shapeworld-train', '--model', 't-vgg', option, value)
    assert_one_line_error(r, 'spatial-grounding shapeworld-train: error:', needle)


def test_rl_options_are_the_config_fields():
    """`rl-train` has one option per RLConfig field, with the field's default and help."""
    from dataclasses import fields

    from spatial_grounding_ros.cli import build_parser
    from spatial_grounding_ros.training.options import from_options
    from spatial_grounding_ros.training.rl import RLConfig

    args = build_parser().parse_args(['rl-train', '--task', 'pw', '--model', 't-cnn'])
    assert from_options(RLConfig, args) == RLConfig()
    assert RLConfig().episodes == 16_000  # the README's RL table ran with this default
    args = build_parser().parse_args(
        ['rl-train', '--task', 'pw', '--model', 't-cnn', '--no-mirrors', '--step-limit', '7']
    )
    assert from_options(RLConfig, args) == RLConfig(mirrors=False, step_limit=7)
    assert all(f.metadata['help'] for f in fields(RLConfig))
    with pytest.raises(ValueError, match='envs must be at least 1, got 0'):
        RLConfig(envs=0)
