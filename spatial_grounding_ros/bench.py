# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
`spatial-grounding bench`: how fast and how lean the grounder is.

- forward latency of the model (one map, one instruction, no_grad) for growing map sizes;
- throughput of one batched forward over 512 maps of 10x10;
- end-to-end ROS latency, instruction published -> goal_pose received (ros/bench_ros.py);
- memory: this process's RSS after 100 and after 10,000 Grounder.ground() requests.
Results go to one JSON file with the machine's description; targets are checked in it.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
import platform
import resource
import time

import numpy as np
import torch
from tqdm import tqdm

from .generator import generate, global_goals, local_goals, random_grid
from .grounder import DEFAULT_CHECKPOINT, Grounder

SIZES = (10, 32, 64, 128, 256)
TARGETS = {
    'forward_10x10_p50_ms': 2.0,
    'forward_128x128_p50_ms': 100.0,
    'ros_end_to_end_p99_ms': 20.0,
    'rss_growth_mb': 20.0,
}


def rss_mb() -> float:
    """Return this process's resident set size now (Linux /proc), in MB."""
    with open('/proc/self/status') as status:
        for line in status:
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) / 1024
    raise RuntimeError('no VmRSS in /proc/self/status')


def peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


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
        'python': platform.python_version(),
        'platform': platform.platform(),
        'load_average_at_start': list(os.getloadavg()),
    }


def world_of_size(size: int, seed: int = 0) -> tuple[np.ndarray, str]:
    """
    Return a generated PuddleWorld-style `size` x `size` grid with one of its instructions.

    A generated PuddleWorld-style grid of `size` x `size` with one of its own instructions
    (objects scale with the area so large maps are not empty grass).
    """
    rng = np.random.default_rng(seed)
    while True:
        grid = random_grid(rng, size, n_nonunique=max(8, size * size // 12))
        goals = global_goals(grid) or local_goals(grid)
        if goals:
            return grid, goals[0][0]


def percentiles(seconds: list[float]) -> dict:
    ms = np.array(seconds) * 1e3
    return {
        'n': len(ms),
        'p50_ms': float(np.percentile(ms, 50)),
        'p99_ms': float(np.percentile(ms, 99)),
        'max_ms': float(ms.max()),
    }


@torch.no_grad()
def forward_latency(grounder: Grounder, size: int, budget_s: float, max_reps: int) -> dict:
    """Model forward (with the relation map and attention, as the node asks) on one map."""
    grid, text = world_of_size(size)
    grids = torch.as_tensor(grid)[None]
    tokens = torch.as_tensor(grounder.vocab.encode_batch([text]))
    grounder.model(grids, tokens, return_aux=True)  # warm-up: the first call pays set-up costs
    start = time.perf_counter()
    grounder.model(grids, tokens, return_aux=True)  # the time of one call sets the count
    reps = int(min(max_reps, max(3, budget_s / (time.perf_counter() - start))))
    times = []
    for _ in tqdm(range(reps), desc=f'forward {size}x{size}', leave=False):
        t0 = time.perf_counter()
        grounder.model(grids, tokens, return_aux=True)
        times.append(time.perf_counter() - t0)
    return {
        'map': f'{size}x{size}',
        'instruction': text,
        **percentiles(times),
        'peak_rss_mb_so_far': peak_rss_mb(),
    }


@torch.no_grad()
def batch_throughput(grounder: Grounder, batch: int, reps: int) -> dict:
    data = generate(batch, seed=1, mode='mixed')
    grids = torch.as_tensor(data.grids)
    tokens = torch.as_tensor(grounder.vocab.encode_batch(data.instructions))
    grounder.model(grids, tokens)  # warm-up
    times = []
    for _ in tqdm(range(reps), desc=f'batch of {batch}', leave=False):
        t0 = time.perf_counter()
        grounder.model(grids, tokens)
        times.append(time.perf_counter() - t0)
    median = float(np.median(times))
    return {
        'batch': batch,
        'map': '10x10',
        'reps': reps,
        'median_batch_ms': median * 1e3,
        'maps_per_second': batch / median,
    }


def memory_growth(grounder: Grounder, early: int, total: int) -> dict:
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


def run(args) -> dict:
    if args.threads > 0:
        torch.set_num_threads(args.threads)
    grounder = Grounder.from_checkpoint(args.checkpoint)
    result = {
        'arguments': {k: v for k, v in vars(args).items() if k != 'func'},
        'machine': machine(),
        'model': grounder.loaded.name,
        'checkpoint_header': {
            k: grounder.loaded.header.get(k) for k in ('task', 'best_epoch', 'val_metrics')
        },
        'targets': TARGETS,
    }
    result['forward'] = [
        forward_latency(grounder, size, args.budget, max_reps=300)
        for size in tqdm(args.sizes, desc='forward latency')
    ]
    result['throughput'] = batch_throughput(grounder, args.batch, args.batch_reps)
    if not args.skip_ros:
        from .ros.bench_ros import round_trip_latency

        grid, _ = world_of_size(10, seed=3)
        texts = [text for text, _ in global_goals(grid) + local_goals(grid)]
        with tqdm(total=args.ros_requests, desc='ROS round trips') as progress:
            result['ros_end_to_end'] = round_trip_latency(
                args.checkpoint, grid, texts, args.ros_requests, progress=progress
            )
    result['memory'] = memory_growth(grounder, 100, args.memory_requests)
    result['checks'] = checks(result)
    return result


def checks(result: dict) -> dict:
    by_map = {f['map']: f for f in result['forward']}
    measured = {
        'forward_10x10_p50_ms': by_map.get('10x10', {}).get('p50_ms'),
        'forward_128x128_p50_ms': by_map.get('128x128', {}).get('p50_ms'),
        'ros_end_to_end_p99_ms': result.get('ros_end_to_end', {}).get('p99_ms'),
        'rss_growth_mb': result['memory']['rss_growth_mb'],
    }
    return {
        k: {'measured': v, 'target': TARGETS[k], 'met': None if v is None else v <= TARGETS[k]}
        for k, v in measured.items()
    }


def cmd_bench(args) -> int:
    result = run(args)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=2) + '\n')
    for name, check in result['checks'].items():
        measured = 'not measured' if check['measured'] is None else f'{check["measured"]:.2f}'
        state = {True: 'met', False: 'MISSED', None: '-'}[check['met']]
        print(f'{name}: {measured} (target <= {check["target"]}) {state}')
    print(f'wrote {out}')
    return 0


def register_cli(subparsers) -> None:
    b = subparsers.add_parser('bench', help='latency, throughput, ROS round trip and memory')
    b.add_argument('--out', default='results/bench.json')
    b.add_argument('--checkpoint', default=DEFAULT_CHECKPOINT)
    b.add_argument('--sizes', nargs='+', type=int, default=list(SIZES))
    b.add_argument(
        '--budget',
        type=float,
        default=10.0,
        help='seconds of forward passes per map size (at least 3, at most 300)',
    )
    b.add_argument('--batch', type=int, default=512, help='maps of 10x10 in the batched forward')
    b.add_argument('--batch-reps', type=int, default=5)
    b.add_argument('--ros-requests', type=int, default=300)
    b.add_argument('--memory-requests', type=int, default=10_000)
    b.add_argument(
        '--threads',
        type=int,
        default=1,
        help="torch threads for the in-process measurements (the node's default "
        "torch_threads is 1 too); 0: torch's default",
    )
    b.add_argument('--skip-ros', action='store_true', help='no end-to-end ROS measurement')
    b.set_defaults(func=cmd_bench)
