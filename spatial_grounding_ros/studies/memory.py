# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The bench's memory measures: growth over many groundings, and one large map's peak.

The peak of grounding one large map is taken in a process that does only that, as a node
does: `python -m spatial_grounding_ros.studies.memory CHECKPOINT SIZE` prints it as JSON. The
bench process's own peak at a size holds what it kept of the sizes and reference forwards
before (glibc keeps freed memory), so the bench asks this one for its memory target.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time

import torch
from tqdm import tqdm

from .measure import peak_rss_mb, reset_peak_rss, rss_mb
from ..core.allocator import keep_freed_memory
from ..data.generator import generate, world_of_size
from ..grounder import Grounder

GROUNDINGS = 3  # the first with a new instruction, then cached, as a node grounds a map again


def memory_growth(grounder, early: int, total: int) -> dict:
    """Return this process's RSS after `early` and after `total` groundings of 10x10 maps."""
    if total <= early:
        raise ValueError(f'--memory-requests must be more than {early}')
    data = generate(100, seed=2, mode='mixed')
    rss = {}
    for i in tqdm(range(total), desc='memory', leave=False):
        grounder.ground(data.grids[i % len(data)], data.instructions[i % len(data)])
        if i + 1 in (early, total):
            rss[i + 1] = rss_mb()
    return {
        'measured': f'RSS of the bench process after {early} and after {total} '
        'Grounder.ground() calls (10x10 generated maps, 100 distinct '
        'map/instruction pairs in turn), the Python API the node calls',
        f'rss_mb_after_{early}': rss[early],
        f'rss_mb_after_{total}': rss[total],
        'rss_growth_mb': rss[total] - rss[early],
    }


def peak_memory(checkpoint: str, size: int) -> dict:
    """Ground a `size` x `size` bench map GROUNDINGS times; the process's RSS before and peak."""
    keep_freed_memory()  # as the node and the bench set it
    torch.set_num_threads(1)
    grounder = Grounder.from_checkpoint(checkpoint)
    grid, text = world_of_size(size)
    before = rss_mb()
    reset_peak_rss()
    seconds = []
    for _ in range(GROUNDINGS):
        start = time.perf_counter()
        grounder.ground(grid, text)
        seconds.append(time.perf_counter() - start)
    return {
        'map': f'{size}x{size}',
        'groundings': GROUNDINGS,
        'rss_mb_before': before,
        'peak_rss_mb': peak_rss_mb(),
        'ground_ms': [s * 1e3 for s in seconds],
        'measured': 'a process of its own: the grounder loaded, then the map grounded '
        f'{GROUNDINGS} times (a new instruction, then cached); its peak RSS (VmHWM) over them',
    }


def in_own_process(checkpoint: str, size: int) -> dict:
    """Return peak_memory(checkpoint, size) as measured in a fresh Python process."""
    done = subprocess.run(
        [sys.executable, '-m', __name__, checkpoint, str(size)],
        capture_output=True,
        text=True,
        check=False,
    )
    if done.returncode != 0:
        raise RuntimeError(f'peak memory of {size}x{size} failed: {done.stderr.strip()[-500:]}')
    return json.loads(done.stdout.strip().splitlines()[-1])


if __name__ == '__main__':
    print(json.dumps(peak_memory(sys.argv[1], int(sys.argv[2]))))
