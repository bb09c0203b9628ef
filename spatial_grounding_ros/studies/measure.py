# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Latency percentiles and process memory, for `spatial-grounding bench` and its ROS half.

Imports nothing of the package, so bench.py and ros/bench_ros.py can both use it without
importing each other (test_layers.py forbids the cycle). Memory is read from Linux /proc.
"""

from __future__ import annotations

import numpy as np


def percentiles(seconds: list[float]) -> dict:
    """Return the count, p50, p99, max and mean of `seconds`, in milliseconds."""
    ms = np.array(seconds) * 1e3
    return {
        'n': len(ms),
        'p50_ms': float(np.percentile(ms, 50)),
        'p99_ms': float(np.percentile(ms, 99)),
        'max_ms': float(ms.max()),
        'mean_ms': float(ms.mean()),
    }


def status_mb(field: str, pid: int | str = 'self') -> float:
    """Return a memory line of /proc/<pid>/status (VmRSS: now, VmHWM: peak), in MB."""
    with open(f'/proc/{pid}/status') as status:
        for line in status:
            if line.startswith(f'{field}:'):
                return int(line.split()[1]) / 1024
    raise RuntimeError(f'no {field} in /proc/{pid}/status')


def rss_mb(pid: int | str = 'self') -> float:
    """Return a process's resident set size now, in MB (this process's by default)."""
    return status_mb('VmRSS', pid)


def reset_peak_rss() -> None:
    """Start the peak RSS (VmHWM) again from the RSS now (Linux: clear_refs 5)."""
    with open('/proc/self/clear_refs', 'w') as clear_refs:
        clear_refs.write('5')


def peak_rss_mb() -> float:
    """Return this process's peak RSS since the last reset_peak_rss(), in MB."""
    return status_mb('VmHWM')
