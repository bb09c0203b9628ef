# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
`spatial-grounding bench`: how fast and how lean the grounder is.

- per map size (10 to 1024): a fixed yardstick (a paper-sized output network on one map), the
  output network alone, Grounder.ground with a cached and with a new instruction (and with
  the map's mirror images on every map, up to mirror_average_cells), the model's fast forward
  and its pair-by-pair reference (where one call fits --reference-max-call), in the same run,
  so their ratios hold across machines; the peak RSS of grounding at that size (the largest's
  also in a process of its own, studies/memory.py: the memory target's);
- the reading of a new ten-word instruction;
- throughput of one batched forward over 512 maps of 10x10;
- one training step (forward, loss, backward, Adam) on a batch of 64 generated 10x10 maps, with
  attention off (the warm-up epochs) and on, for a fresh model of the checkpoint's config;
- end-to-end ROS latency, instruction published -> goal_pose received, measured by the
  function cli.py passes in (ros/bench_ros.py's round_trip_latency; studies sit below ros),
  as shipped and with mirror averaging, each with the load average at its start;
- memory: this process's RSS after 100 and after 10,000 Grounder.ground() requests.
Results go to one JSON file with the machine's description and which targets were met, and its
table to a markdown file beside it (the README's benchmark table).
"""

from __future__ import annotations

import functools
import json
import os
from pathlib import Path
import time
from typing import Callable

import numpy as np
import torch
from tqdm import tqdm

from .measure import (
    machine, peak_rss_mb, reset_peak_rss, timed, timed_together, yardstick
)
from .memory import in_own_process, memory_growth
from ..data.generator import generate, global_goals, local_goals, world_of_size
from ..grounder import CACHED_INSTRUCTIONS, DEFAULT_CHECKPOINT, Grounder, IMAGES
from ..language import grammar
from ..models.config import ModelConfig
from ..models.registry import build_model
from ..training.options import ranged

SIZES = (10, 32, 64, 128, 256, 512, 1024)
# issue 44's minimum: Grounder.ground (cached instruction) against a fixed yardstick timed in
# the same run (yardstick()), the largest map's time and memory, the node's round trip
TARGETS = {
    'ground_over_yardstick_10x10': 5.0,
    'ground_over_yardstick_128x128': 2.5,
    'ground_over_yardstick_512x512': 1.5,
    'ground_1024x1024_ms': 1200.0,
    'peak_rss_1024x1024_mb': 1024.0,
    'reading_10_words_ms': 1.0,
    'ros_end_to_end_p50_ms': 2.5,
    'ros_end_to_end_p99_ms': 5.0,
    'rss_growth_mb': 20.0,
}
# instructions in turn for the node's round trip with instructions it has grounded before
REPEATED = 8
# a ten-word instruction of the grammar people use, for the reading's time
TEN_WORDS = 'two cells north-east of the second rock from the left'


@torch.no_grad()
def size_latency(grounder: Grounder, size: int, args, reference_s_per_cell: float) -> dict:
    """
    Time every way of grounding one `size` x `size` map, the output network and the yardstick.

    The yardstick, the output network (as run) and Grounder.ground with a cached instruction
    run in turn (timed_together). The reference runs when one call, predicted from the last
    size's seconds per cell (0: run it), fits args.reference_max_call.
    """
    grid, text = world_of_size(size)
    grids = torch.as_tensor(grid)[None]
    tokens = torch.as_tensor(grounder.vocab.encode_batch([text]))
    model = grounder.model
    images = images_grounded(grounder, grid, text)
    z1 = torch.randn(images, size, size)
    code = torch.randn(images, model.head.code_size)  # what an instruction gives the head
    # the far relation's map, for a head that reads one
    far = torch.randn(images, size, size) if model.head.inputs == 3 else None
    gradients = torch.randn(1, 2, size, size)
    stick = yardstick()

    def new_instruction():
        grounder.text_codes.clear()
        grounder.ground(grid, text)

    def run(call, what):
        return timed(call, args.budget, 300, f'{what} {size}x{size}')

    row = {'map': f'{size}x{size}', 'instruction': text, 'images': images}
    reset_peak_rss()
    row.update(
        timed_together(
            {
                'yardstick': lambda: stick(gradients),
                'head': lambda: model.head(z1, code, far),
                'ground_cached': lambda: grounder.ground(grid, text),
            },
            args.budget * 3,
            300,
            f'yardstick, output network, ground {size}x{size}',
        )
    )
    row['peak_rss_mb'] = peak_rss_mb()
    row['ground_over_yardstick'] = row['ground_cached']['p50_ms'] / row['yardstick']['p50_ms']
    row['ground_over_head'] = row['ground_cached']['p50_ms'] / row['head']['p50_ms']
    # the output network alone, as the model runs it (channels-last, tiled) and plain
    row['head_plain'] = run(
        lambda: model.head(z1, code, far, layout=torch.contiguous_format), 'plain head'
    )
    row['ground_new'] = run(new_instruction, 'ground, new instruction')
    if size * size <= grounder.mirror_average_cells:  # with the mirror images on every map
        below, grounder.mirror_average_below = grounder.mirror_average_below, 1.0
        row['ground_mirrored'] = run(lambda: grounder.ground(grid, text), 'ground, mirrored')
        grounder.mirror_average_below = below
    row['forward'] = run(lambda: model(grids, tokens, return_aux=True), 'forward')
    if hasattr(model, 'pair_forward'):
        if reference_s_per_cell * size * size <= args.reference_max_call:
            reset_peak_rss()
            row['reference'] = run(
                lambda: model(grids, tokens, return_aux=True, reference=True), 'reference'
            )
            row['reference_peak_rss_mb'] = peak_rss_mb()
            row['reference_over_forward'] = row['reference']['p50_ms'] / row['forward']['p50_ms']
            row['reference_over_ground'] = (
                row['reference']['p50_ms'] / row['ground_cached']['p50_ms']
            )
        else:
            row['reference'] = None  # predicted over the budget: not run
    return row


def images_grounded(grounder: Grounder, grid: np.ndarray, text: str) -> int:
    """Return how many images of the map the grounder runs for an instruction (1 or 4)."""
    before = grounder.mirror_averaged
    grounder.ground(grid, text)
    return len(IMAGES) if grounder.mirror_averaged > before else 1


def reading(grounder: Grounder, budget_s: float) -> dict:
    """Time the reading of a new ten-word instruction (Reader.read, its caches bypassed)."""
    words = len(TEN_WORDS.split())

    def read_new():
        grounder.reader.lexicon.found.cache_clear()  # the landmarks found in its word lists
        grammar.landmark_cache_clear()  # the landmarks its places name
        grounder.reader._read(TEN_WORDS)

    result = timed(read_new, budget_s, 1000, 'reading')
    return {'instruction': TEN_WORDS, 'words': words, **result}


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


def training_step(grounder: Grounder, batch: int, budget_s: float) -> dict:
    """
    Time one training step of a fresh model of the checkpoint's kind: attention off and on.

    A batch of `batch` generated 10x10 maps (every family), the MSE, the backward and an Adam
    step, as `train` takes them (its attention warm-up trains with attention off).
    """
    loaded = grounder.loaded
    torch.manual_seed(0)
    model = build_model(loaded.name, ModelConfig.from_dict(loaded.header['config'])).train()
    data = generate(batch, seed=3, mode='mixed', size=10)
    grids = torch.as_tensor(data.grids)
    tokens = torch.as_tensor(grounder.vocab.encode_batch(data.instructions))
    values = torch.as_tensor(data.values)
    opt = torch.optim.Adam(model.parameters(), lr=1e-3)

    def step():
        loss = torch.mean((model(grids, tokens) - values) ** 2)
        opt.zero_grad()
        loss.backward()
        opt.step()

    result = {'batch': batch, 'map': '10x10', 'model': loaded.name}
    with_attention = model.capabilities.relation_attention  # t-RNetAttn; the others have none
    for name in ('attention_off', 'attention_on') if with_attention else ('attention_off',):
        if with_attention:
            model.attention_on = name == 'attention_on'
        if name == 'attention_on':  # as trained: its projection away from the zero start
            torch.nn.init.normal_(model.attn.weight)
        result[name] = timed(step, budget_s, 300, f'training step, {name.replace("_", " ")}')
    return result


def run(args, ros_latency: Callable[..., dict] | None = None) -> dict:
    """
    Measure every section `args` asks for and return the results, checked against TARGETS.

    `ros_latency(checkpoint, grid, instructions, requests, progress=...)` measures the ROS round
    trip (cli.py passes ros/bench_ros.py's); without it only --skip-ros runs.
    """
    if not args.skip_ros and ros_latency is None:
        raise ValueError('bench has no ROS measurement here: pass --skip-ros')
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
        'sizes': [],
    }
    reference_s_per_cell = 0.0
    for size in tqdm(args.sizes, desc='map sizes'):
        row = size_latency(grounder, size, args, reference_s_per_cell)
        if row.get('reference'):
            reference_s_per_cell = row['reference']['p50_ms'] / 1e3 / size**2
        result['sizes'].append(row)
    # this process keeps what earlier sizes and reference forwards took: not the node's case
    result['fresh_process'] = in_own_process(args.checkpoint, max(args.sizes))
    result['reading'] = reading(grounder, args.budget)
    result['throughput'] = batch_throughput(grounder, args.batch, args.batch_reps)
    result['training_step'] = training_step(grounder, args.train_batch, args.budget)
    if not args.skip_ros:
        grid, _ = world_of_size(10, seed=3)
        texts = [text for text, _ in global_goals(grid) + local_goals(grid)]
        # more instructions in turn than a Grounder keeps: each request is new to the node
        if len(texts) <= CACHED_INSTRUCTIONS:
            raise RuntimeError(f'{len(texts)} instructions: each would not be new to the node')
        # rclpy and DDS alone (an echo node), the node as shipped (new instructions, then a few
        # it has grounded before), then with the mirror images on every map, in one run
        for key, options, said in (
            ('ros_echo', {'echo': True}, texts),
            ('ros_end_to_end', {}, texts),
            ('ros_end_to_end_repeated', {}, texts[:REPEATED]),
            ('ros_end_to_end_mirrored', {'parameters': ('mirror_average_below:=1.0',)}, texts),
        ):
            load = os.getloadavg()[0]
            with tqdm(total=args.ros_requests, desc=key.replace('_', ' ')) as progress:
                result[key] = ros_latency(
                    args.checkpoint, grid, said, args.ros_requests, progress=progress, **options
                )
            result[key]['load_average_at_start'] = load
    result['memory'] = memory_growth(grounder, 100, args.memory_requests)
    result['checks'] = checks(result)
    return result


def checks(result: dict) -> dict:
    by_map = {row['map']: row for row in result['sizes']}
    ros, largest = result.get('ros_end_to_end', {}), by_map.get('1024x1024', {})
    own = result.get('fresh_process', {}) if largest else {}  # its memory in a process of its own
    measured = {
        **{
            f'ground_over_yardstick_{size}': by_map.get(size, {}).get('ground_over_yardstick')
            for size in ('10x10', '128x128', '512x512')
        },
        'ground_1024x1024_ms': largest.get('ground_cached', {}).get('p50_ms'),
        'peak_rss_1024x1024_mb': own.get('peak_rss_mb'),
        'reading_10_words_ms': result.get('reading', {}).get('p50_ms'),
        'ros_end_to_end_p50_ms': ros.get('p50_ms'),
        'ros_end_to_end_p99_ms': ros.get('p99_ms'),
        'rss_growth_mb': result['memory']['rss_growth_mb'],
    }
    return {
        k: {'measured': v, 'target': TARGETS[k], 'met': None if v is None else v <= TARGETS[k]}
        for k, v in measured.items()
    }


def check_text(check: dict) -> str:
    state = {True: 'met', False: 'MISSED', None: 'not measured'}[check['met']]
    return f'target <= {check["target"]:g}: {state}'


def table(result: dict) -> str:
    """Return the benchmark table of a result in markdown, with its caption lines."""
    checks_ = result['checks']
    lines = [
        '| map | images | yardstick | output network alone: plain / as run | Grounder.ground, '
        'cached instruction | ground / yardstick | ground / network | with mirror images '
        '| new instruction | model forward | reference forward | reference / forward '
        '| peak RSS |',
        '| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |',
    ]
    for row in result['sizes']:
        reference = row.get('reference')
        mirrored = row.get('ground_mirrored')
        lines.append(
            f'| {row["map"]} | {row["images"]} | {row["yardstick"]["p50_ms"]:.3g} ms '
            f'| {row["head_plain"]["p50_ms"]:.3g} / {row["head"]["p50_ms"]:.3g} ms '
            f'| {row["ground_cached"]["p50_ms"]:.3g} ms | {row["ground_over_yardstick"]:.2f} '
            f'| {row["ground_over_head"]:.2f} '
            + (f'| {mirrored["p50_ms"]:.3g} ms ' if mirrored else '| ')
            + f'| {row["ground_new"]["p50_ms"]:.3g} ms '
            f'| {row["forward"]["p50_ms"]:.3g} ms '
            + (
                f'| {reference["p50_ms"]:.3g} ms | {row["reference_over_forward"]:.1f}x '
                if reference
                else '| not run | '
            )
            + f'| {row["peak_rss_mb"]:.0f} MB |'
        )
    by_map = {row['map']: row for row in result['sizes']}
    for size in ('10x10', '128x128', '512x512'):
        if size in by_map:
            check = checks_[f'ground_over_yardstick_{size}']
            lines.append(
                f'Grounder.ground / yardstick at {size}: {check["measured"]:.2f} '
                f'({check_text(check)}); / its output network: '
                f'{by_map[size]["ground_over_head"]:.2f}.'
            )
    if '1024x1024' in by_map:
        time_, rss = checks_['ground_1024x1024_ms'], checks_['peak_rss_1024x1024_mb']
        lines.append(
            f'Grounding 1024x1024: {time_["measured"]:.0f} ms ({check_text(time_)}), peak RSS '
            f'{rss["measured"]:.0f} MB in a process of its own ({check_text(rss)}; '
            f'{by_map["1024x1024"]["peak_rss_mb"]:.0f} MB in this one, with what it kept).'
        )
    read = result.get('reading')
    if read:
        lines.append(
            f'Reading a new instruction of {read["words"]} words ("{read["instruction"]}"): '
            f'{read["p50_ms"]:.3f} ms ({check_text(checks_["reading_10_words_ms"])}); then '
            'cached per instruction.'
        )
    throughput = result['throughput']
    lines.append(
        f'Throughput, one batch of {throughput["batch"]} maps of {throughput["map"]}: '
        f'{throughput["maps_per_second"]:.0f} maps/s ({throughput["median_batch_ms"]:.0f} ms '
        'per batch).'
    )
    step = result.get('training_step')
    if step:
        lines.append(
            f'Training step ({step["model"]}, a batch of {step["batch"]} generated maps of '
            f'{step["map"]}: forward, MSE, backward, Adam): '
            + ', '.join(
                f'{step[name]["p50_ms"]:.1f} ms with {name.replace("_", " ")}'
                for name in ('attention_off', 'attention_on')
                if name in step
            )
            + '.'
        )
    lines += ros_lines(result, checks_)
    memory = result['memory']
    early, total = sorted(int(k.split('_')[-1]) for k in memory if k.startswith('rss_mb_after_'))
    lines.append(
        f'Bench process RSS after {early} vs {total:,} Grounder.ground() calls: '
        f'{memory[f"rss_mb_after_{early}"]:.1f} -> {memory[f"rss_mb_after_{total}"]:.1f} MB '
        f'({check_text(checks_["rss_growth_mb"])}).'
    )
    machine_ = result['machine']
    lines.append(
        f'Machine: {machine_["usable_cores"]} {machine_["cpu"]} cores, '
        f'{machine_["torch_threads"]} torch thread, torch {machine_["torch"]}; load average '
        f'{machine_["load_average_at_start"][0]:.1f} at the start.'
    )
    return '\n'.join(lines) + '\n'


def ros_lines(result: dict, checks_: dict) -> list[str]:
    """Return the table's lines on the node's round trips (none if not measured)."""
    lines = []
    ros = result.get('ros_end_to_end')
    if ros:
        lines.append(
            f'ROS end to end, instruction published -> goal_pose received, {ros["map"]}, each '
            f'instruction new to the node: '
            f'p50 {ros["p50_ms"]:.2f} ms ({check_text(checks_["ros_end_to_end_p50_ms"])}), '
            f'p99 {ros["p99_ms"]:.2f} ms ({check_text(checks_["ros_end_to_end_p99_ms"])}), max '
            f'{ros["max_ms"]:.2f} ms ({ros["requests"]} requests, load average '
            f'{ros["load_average_at_start"]:.1f} at its start); grounder node RSS '
            f'{ros["node_rss_mb_after_warmup"]:.0f} -> {ros["node_rss_mb_end"]:.0f} MB.'
        )
    for key, what in (
        ('ros_end_to_end_repeated', f'{REPEATED} instructions in turn, each grounded before'),
        ('ros_end_to_end_mirrored', 'mirror_average_below 1 (every map with its mirror images)'),
        ('ros_echo', 'an echo node in place of the grounder (rclpy and DDS alone, no grounding)'),
    ):
        if result.get(key):
            other = result[key]
            lines.append(
                f'The same with {what}: p50 {other["p50_ms"]:.2f} ms, p99 {other["p99_ms"]:.2f} '
                f'ms, max {other["max_ms"]:.2f} ms (load average '
                f'{other["load_average_at_start"]:.1f}).'
            )
    return lines


def cmd_bench(args, ros_latency: Callable[..., dict] | None = None) -> int:
    result = run(args, ros_latency)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=2) + '\n')
    out.with_suffix('.md').write_text(table(result))
    for name, check in result['checks'].items():
        measured = 'not measured' if check['measured'] is None else f'{check["measured"]:.2f}'
        state = {True: 'met', False: 'MISSED', None: '-'}[check['met']]
        print(f'{name}: {measured} (target <= {check["target"]}) {state}')
    print(f'wrote {out} and {out.with_suffix(".md")}')
    return 0


def register_cli(subparsers, ros_latency: Callable[..., dict] | None = None) -> None:
    """Add the `bench` subcommand; `ros_latency` measures its ROS round trip (see run)."""
    b = subparsers.add_parser(
        'bench', help='fast vs reference latency per map size, throughput, ROS round trip, memory'
    )
    b.add_argument('--out', default='results/bench.json')
    b.add_argument('--checkpoint', default=DEFAULT_CHECKPOINT)
    b.add_argument('--sizes', nargs='+', type=ranged(int, low=1), default=list(SIZES))
    b.add_argument(
        '--budget', type=float, default=5.0, help='seconds of calls per way and map size'
    )
    b.add_argument(
        '--reference-max-call',
        type=float,
        default=5.0,
        help='seconds one reference (pair-by-pair) forward may take, predicted from the '
        'previous size; larger sizes skip it',
    )
    b.add_argument('--batch', type=ranged(int, low=1), default=512, help='maps in one forward')
    b.add_argument('--batch-reps', type=ranged(int, low=1), default=5)
    b.add_argument('--train-batch', type=ranged(int, low=1), default=64, help='maps a step')
    b.add_argument(
        '--ros-requests',
        type=ranged(int, low=1),
        default=1000,
        help='instruction -> goal_pose round trips (1000: the p99 is the 10th slowest, not the '
        '3rd of 300)',
    )
    b.add_argument('--memory-requests', type=ranged(int, low=1), default=10_000)
    b.add_argument(
        '--threads',
        type=ranged(int, low=0),
        default=1,
        help="torch threads for the in-process measurements (the node's default "
        "torch_threads is 1 too); 0: torch's default",
    )
    b.add_argument('--skip-ros', action='store_true', help='no end-to-end ROS measurement')
    b.set_defaults(func=functools.partial(cmd_bench, ros_latency=ros_latency))
