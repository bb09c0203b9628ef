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
from spatial_grounding_ros.checkpoints import PACKAGED_DIR
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


def test_rl_options_are_the_config_fields():
    """`rl-train` has one option per RLConfig field, with the field's default and help."""
    from dataclasses import fields

    from spatial_grounding_ros.cli import build_parser
    from spatial_grounding_ros.options import from_options
    from spatial_grounding_ros.rl import RLConfig

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
