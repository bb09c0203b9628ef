# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
`spatial-grounding bench` with tiny counts.

Every section runs (the ROS round trip against a real grounder process) and the JSON holds the
numbers and the machine they came from.
"""

import json
import os

import pytest
import torch

pytest.importorskip('rclpy', reason='rclpy is not installed')

from grounder_helpers import random_checkpoint  # noqa: E402, I100
from spatial_grounding_ros import cli  # noqa: E402
from spatial_grounding_ros.studies import bench  # noqa: E402


def test_bench_writes_every_section(tmp_path):
    checkpoint = random_checkpoint(tmp_path / 'random.pt')
    out = tmp_path / 'bench.json'
    threads = torch.get_num_threads()
    try:
        assert (
            cli.main(
                [
                    'bench',
                    '--out',
                    str(out),
                    '--checkpoint',
                    str(checkpoint),
                    '--sizes',
                    '10',
                    '16',
                    '--budget',
                    '0.05',
                    '--batch',
                    '16',
                    '--batch-reps',
                    '1',
                    '--train-batch',
                    '4',
                    '--ros-requests',
                    '5',
                    '--memory-requests',
                    '110',
                ]
            )
            == 0
        )
    finally:
        torch.set_num_threads(threads)  # the bench sets 1 (its default) process-wide
    result = json.loads(out.read_text())
    assert result['machine']['cores'] == os.cpu_count()
    assert result['machine']['torch_threads'] == 1
    assert [row['map'] for row in result['sizes']] == ['10x10', '16x16']
    for row in result['sizes']:
        ways = ('yardstick', 'head', 'head_plain', 'ground_cached', 'ground_new', 'forward',
                'reference', 'ground_mirrored')
        for way in ways:
            assert 0 < row[way]['p50_ms'] <= row[way]['p99_ms'] <= row[way]['max_ms'], way
        assert row['ground_over_head'] == row['ground_cached']['p50_ms'] / row['head']['p50_ms']
        assert row['ground_over_yardstick'] == (
            row['ground_cached']['p50_ms'] / row['yardstick']['p50_ms']
        )
        # the yardstick, the network and the grounder ran in turn, as many times each
        assert row['yardstick']['n'] == row['ground_cached']['n'] == row['head']['n']
        assert row['peak_rss_mb'] > 0 and row['reference_peak_rss_mb'] > 0
        # a random network is unsure of every map: it grounds the mirror images too
        assert row['images'] == 4
    reading = result['reading']
    assert reading['words'] == 10 and 0 < reading['p50_ms']
    assert result['throughput']['batch'] == 16 and result['throughput']['maps_per_second'] > 0
    step = result['training_step']
    assert step['batch'] == 4 and step['model'] == 't-rnet-attn'
    assert 0 < step['attention_off']['p50_ms'] and 0 < step['attention_on']['p50_ms']
    ros = result['ros_end_to_end']
    assert ros['requests'] == 5 and 0 < ros['p50_ms'] <= ros['p99_ms']
    assert ros['node_rss_mb_end'] > 0
    repeated = result['ros_end_to_end_repeated']
    assert repeated['requests'] == 5 and 0 < repeated['p50_ms'] <= repeated['p99_ms']
    assert '8 instructions in turn' in repeated['measured']
    mirrored = result['ros_end_to_end_mirrored']
    assert mirrored['requests'] == 5 and 0 < mirrored['p50_ms'] <= mirrored['p99_ms']
    assert ros['load_average_at_start'] >= 0 and mirrored['load_average_at_start'] >= 0
    echo = result['ros_echo']  # the echo node answered each instruction
    assert echo['requests'] == 5 and 0 < echo['p50_ms'] <= echo['p99_ms']
    assert 'the echo node in its own process' in echo['measured']
    assert 'an echo node in place of the grounder' in bench.table(result)
    memory = result['memory']
    assert memory['rss_mb_after_110'] > 0 and 'Grounder.ground()' in memory['measured']
    # the largest map's peak in a process that grounds only it (the memory target's, at 1024)
    own = result['fresh_process']
    assert own['map'] == '16x16' and 0 < own['rss_mb_before'] <= own['peak_rss_mb']
    assert len(own['ground_ms']) == own['groundings'] and min(own['ground_ms']) > 0
    assert set(result['checks']) == set(bench.TARGETS)
    assert result['checks']['ground_over_yardstick_128x128']['met'] is None  # not measured
    assert result['checks']['peak_rss_1024x1024_mb']['met'] is None
    # the markdown table beside the JSON is the JSON's table
    assert out.with_suffix('.md').read_text() == bench.table(result)
    assert '| 16x16 | 4 |' in bench.table(result)
    assert 'Training step (t-rnet-attn, a batch of 4 generated maps' in bench.table(result)


def test_bench_skips_a_reference_over_its_budget(tmp_path):
    """The reference runs at the first size, then only while one call is predicted to fit."""
    out = tmp_path / 'bench.json'
    threads = torch.get_num_threads()
    try:
        arguments = ['bench', '--out', str(out), '--sizes', '10', '40', '--budget', '0.05']
        arguments += ['--batch', '4', '--batch-reps', '1', '--train-batch', '4', '--skip-ros']
        arguments += ['--memory-requests', '101', '--reference-max-call', '1e-6']
        assert cli.main(arguments) == 0
    finally:
        torch.set_num_threads(threads)
    first, second = json.loads(out.read_text())['sizes']
    assert first['reference']['n'] >= 3 and second['reference'] is None
    assert 'not run' in out.with_suffix('.md').read_text()
