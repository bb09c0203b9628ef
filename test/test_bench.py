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
    assert [f['map'] for f in result['forward']] == ['10x10', '16x16']
    assert all(0 < f['p50_ms'] <= f['p99_ms'] <= f['max_ms'] for f in result['forward'])
    assert result['throughput']['batch'] == 16 and result['throughput']['maps_per_second'] > 0
    ros = result['ros_end_to_end']
    assert ros['requests'] == 5 and 0 < ros['p50_ms'] <= ros['p99_ms']
    assert ros['node_rss_mb_end'] > 0
    memory = result['memory']
    assert memory['rss_mb_after_110'] > 0 and 'Grounder.ground()' in memory['measured']
    assert set(result['checks']) == {
        'forward_10x10_p50_ms',
        'forward_128x128_p50_ms',
        'ros_end_to_end_p99_ms',
        'rss_growth_mb',
    }
    assert result['checks']['forward_128x128_p50_ms']['met'] is None  # not measured here
