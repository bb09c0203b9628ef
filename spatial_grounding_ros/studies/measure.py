# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Timing, the fixed yardstick and process memory, for `spatial-grounding bench` and its ROS half.

Imports nothing of the package, so bench.py and ros/bench_ros.py can both use it without
importing each other (test_layers.py forbids the cycle). Memory is read from Linux /proc.
"""

from __future__ import annotations

import os
import platform
import time

import numpy as np
import torch
from tqdm import tqdm


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


def timed(call, budget_s: float, max_reps: int, desc: str) -> dict:
    """Percentiles of `call` over as many runs as fit `budget_s` (3 to max_reps)."""
    return timed_together({desc: call}, budget_s, max_reps, desc)[desc]


def timed_together(calls: dict, budget_s: float, max_reps: int, desc: str) -> dict:
    """
    Percentiles of each of `calls` ({name: call}), their runs taken in turn.

    One run of each after another, so a ratio of two compares them in the same phase of a
    shared machine. As many rounds as fit `budget_s` (3 to max_reps).
    """
    for call in calls.values():
        call()  # warm-up: the first call pays set-up costs
    start = time.perf_counter()
    for call in calls.values():
        call()  # the time of one round sets the count
    reps = int(min(max_reps, max(3, budget_s / (time.perf_counter() - start))))
    times = {name: [] for name in calls}
    for _ in tqdm(range(reps), desc=desc, leave=False):
        for name, call in calls.items():
            t0 = time.perf_counter()
            call()
            times[name].append(time.perf_counter() - t0)
    return {name: percentiles(t) for name, t in times.items()}


def yardstick() -> torch.nn.Module:
    """
    Return the fixed yardstick: a paper-sized output network on one map, in eval mode.

    3x3 convolutions of 2, 8, 16, 32, 16, 8 and 1 channels with leaky ReLUs between: the
    shape of the output network of the paper's code, on the map's two gradient channels. Its
    time, taken in the same run, makes the grounder's a ratio that holds across machines and
    the VM's fast and slow phases.
    """
    torch.manual_seed(0)
    channels = (2, 8, 16, 32, 16, 8, 1)
    layers = []
    for a, b in zip(channels[:-1], channels[1:]):
        layers += [torch.nn.Conv2d(a, b, 3, padding=1), torch.nn.LeakyReLU(0.01)]
    return torch.nn.Sequential(*layers[:-1]).eval()


def machine() -> dict:
    model = next(
        (
            line.split(':', 1)[1].strip()
            for line in open('/proc/cpuinfo')
            if line.startswith('model name')
        ),
        platform.processor(),
    )
    return {
        'cpu': model,
        'cores': os.cpu_count(),
        'usable_cores': len(os.sched_getaffinity(0)),
        'torch_threads': torch.get_num_threads(),
        'torch': torch.__version__,
        # the kernels torch picked (AVX2, AVX512): float sums, and so trained weights, differ
        'cpu_capability': torch.backends.cpu.get_cpu_capability(),
        'python': platform.python_version(),
        'platform': platform.platform(),
        'load_average_at_start': list(os.getloadavg()),
    }
