# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
`spatial-grounding`: one command, with subcommands.

Bad input (missing or corrupt files, unknown names, mismatched checkpoints) prints one
line `spatial-grounding: error: ...` and exits with status 2, without a traceback.
"""

from __future__ import annotations

import argparse
import functools
import json
import sys

from .core.allocator import keep_freed_memory
from .core.tasks import TASKS
from .data.datasets import DEFAULT_DATA, SPLITS


def cmd_train(args) -> int:
    from .training import distributed
    from .training.options import given_options
    from .training.recipe import recipe, TrainConfig
    from .training.supervised import train_supervised

    tc = TrainConfig(**given_options(TrainConfig, args))  # the rest: the task's values
    if args.show_config:  # the run resolved, without training it
        run = recipe(args.task, args.model, tc)
        print(json.dumps(run.to_dict(), indent=2) if args.json else '\n'.join(run.lines()))
        return 0
    path, summary = train_supervised(args.task, args.model, args.data, args.out, tc)
    if distributed.is_main_process():  # under torchrun, one summary, not one per process
        print(json.dumps({'checkpoint': str(path), **summary}, indent=2))
    return 0


def cmd_eval(args) -> int:
    from .data.datasets import load_task
    from .data.noise import add_noise, NOISES, require_unseen_rows
    from .models.checkpoints import load_checkpoint
    from .training.supervised import evaluate

    data = load_task(args.task, args.split, args.data)
    loaded = load_checkpoint(args.checkpoint, expect_entities=data.entities)
    noise = {name: getattr(args, name.replace('-', '_')) for name in NOISES}
    if noise['obs-noise']:
        require_unseen_rows(loaded.model, loaded.name)
    for name, k in noise.items():
        data = add_noise(data, loaded.vocab, name, k, args.seed)
    metrics = {
        'checkpoint': str(args.checkpoint),
        'model': loaded.name,
        'task': args.task,
        'split': args.split,
        **({'noise': noise, 'seed': args.seed} if any(noise.values()) else {}),
        **evaluate(loaded.model, loaded.vocab, data),
    }
    if args.json:
        print(json.dumps(metrics))
    else:
        print(
            f'{loaded.name} on {args.task} {args.split} (n={metrics["n"]}): '
            f'MSE {metrics["mse"]:.3f}  PQ {metrics["pq"]:.3f}  MD {metrics["md"]:.2f}  '
            f'HIT {metrics["hit"]:.3f}'
        )
    return 0


def cmd_reproduce(args) -> int:
    from .studies.reproduce import reproduce_ablation, reproduce_suite, reproduce_value_maps

    if args.ablation:
        reproduce_ablation(args.data, args.out, threads=args.jobs)
        return 0
    if args.suite_only:
        reproduce_suite(args.out)
        return 0
    reproduce_value_maps(
        args.data, args.out, args.epochs_scale, args.tasks, args.models, args.jobs
    )
    return 0


def cmd_rl_train(args) -> int:
    from .training.env import load_episodes
    from .training.options import from_options
    from .training.rl import RLConfig, train_rl

    cfg = from_options(RLConfig, args)
    train = test = None
    if args.task.startswith('generator'):
        train = load_episodes(args.task, n=args.generated, seed=cfg.seed)
        test = load_episodes(args.task, n=max(50, args.generated // 5), seed=cfg.seed + 1000)
    run = functools.partial(
        train_rl, args.task, args.model, args.data, args.out, cfg, train, test,
        progress=not args.quiet,
    )
    if args.via_ros:
        from .ros.gridworld_client import ros_envs

        with ros_envs(args.task, args.data, train, cfg, cfg.seed) as envs:
            path, summary = run(envs=envs)
    else:
        path, summary = run()
    print(json.dumps({'checkpoint': str(path), **summary}))
    return 0


def cmd_reproduce_rl(args) -> int:
    from .studies.reproduce import reproduce_rl

    reproduce_rl(
        args.data, args.out, args.tasks, args.models, args.episodes_scale, args.jobs,
        args.checkpoints,
    )
    return 0


class _Parser(argparse.ArgumentParser):
    """Usage mistakes are one line and exit status 2, like every other bad input."""

    def error(self, message):
        self.exit(2, f'{self.prog}: error: {message}\n')


def build_parser() -> argparse.ArgumentParser:
    from .data.noise import add_noise_options
    from .models.registry import MODELS
    from .training.options import add_options, ranged
    from .training.recipe import TrainConfig

    p = _Parser(prog='spatial-grounding', description=__doc__.strip().splitlines()[0])
    sub = p.add_subparsers(dest='command', required=True, parser_class=_Parser)

    t = sub.add_parser(
        'train',
        help="supervised training on a task's train split",
        description="Supervised training on a task's train split. An option not given takes "
        "the task's value (tasks.py). ShapeWorld has its own: shapeworld-train.",
    )
    t.add_argument('--task', required=True, choices=list(TASKS))
    t.add_argument('--model', required=True, choices=list(MODELS))
    t.add_argument('--data', default=DEFAULT_DATA)
    t.add_argument('--out', default='out')
    t.add_argument(
        '--show-config',
        action='store_true',
        help='print every setting of the run (training, model, data; the options given over '
        "the task's) and exit without training",
    )
    t.add_argument('--json', action='store_true', help='--show-config as one JSON object')
    add_options(t, TrainConfig, unset=True)
    t.set_defaults(func=cmd_train)

    e = sub.add_parser('eval', help='evaluate a checkpoint on a split')
    e.add_argument('--checkpoint', required=True)
    e.add_argument('--task', required=True, choices=list(TASKS))
    e.add_argument('--split', default='test', choices=SPLITS)
    e.add_argument('--data', default=DEFAULT_DATA)
    e.add_argument('--json', action='store_true', help='print exactly one JSON object')
    add_noise_options(e)
    e.set_defaults(func=cmd_eval)

    r = sub.add_parser('reproduce', help='train and evaluate the value-map table')
    r.add_argument('--data', default=DEFAULT_DATA)
    r.add_argument('--out', default='results')
    r.add_argument('--tasks', nargs='+', default=list(TASKS), choices=TASKS)
    r.add_argument('--models', nargs='+', default=list(MODELS), choices=list(MODELS))
    r.add_argument(
        '--epochs-scale',
        type=ranged(float, low=0.001),
        default=1.0,
        help='multiply every epoch budget (e.g. 0.1 for a quick check)',
    )
    r.add_argument(
        '--jobs',
        type=ranged(int, low=1),
        default=2,
        help='training runs at a time, one thread each (--ablation: one run on this many threads)',
    )
    r.add_argument(
        '--suite-only',
        action='store_true',
        help='only run the reference suite on the shipped checkpoints (results/suite.*)',
    )
    r.add_argument(
        '--ablation',
        action='store_true',
        help='only the clear-references ablation: t-RNet on pw, each change of the '
        'recipe off in turn, one training run each (results/ablation.*)',
    )
    r.set_defaults(func=cmd_reproduce)

    add_rl_commands(sub)
    for register in _extensions():
        register(sub)
    return p


def add_rl_commands(sub) -> None:
    from .core.tasks import RL_TASKS
    from .models.registry import MODELS
    from .training.env import GENERATED
    from .training.options import add_options, ranged
    from .training.rl import RLConfig

    p = sub.add_parser('rl-train', help='train a model by RL (fitted value iteration)')
    p.add_argument('--task', required=True, choices=[*TASKS, *GENERATED])
    p.add_argument('--model', required=True, choices=list(MODELS))
    p.add_argument('--data', default=DEFAULT_DATA)
    p.add_argument('--out', default='out')
    add_options(p, RLConfig)
    p.add_argument(
        '--generated',
        type=ranged(int, low=1),
        default=500,
        help='number of generated training examples (generator* tasks)',
    )
    p.add_argument(
        '--via-ros', action='store_true', help="run episodes through the gridworld node's topics"
    )
    p.add_argument('--quiet', action='store_true')
    p.set_defaults(func=cmd_rl_train)

    r = sub.add_parser(
        'reproduce-rl',
        help="RL rows of the paper's table: train, evaluate, write rl.json and rl.md",
    )
    r.add_argument('--data', default=DEFAULT_DATA)
    r.add_argument('--out', default='results')
    r.add_argument('--checkpoints', default='out', help='where the RL checkpoints go')
    r.add_argument('--tasks', nargs='+', default=list(RL_TASKS), choices=RL_TASKS)
    r.add_argument('--models', nargs='+', default=['t-rnet-attn', 't-cnn'], choices=list(MODELS))
    r.add_argument(
        '--episodes-scale',
        type=ranged(float, low=0.001),
        default=1.0,
        help='multiply every episode budget (e.g. 0.05 for a quick check)',
    )
    r.add_argument(
        '--jobs', type=ranged(int, low=1), default=2, help='runs in parallel, one thread each'
    )
    r.set_defaults(func=cmd_reproduce_rl)


def ros_round_trip_latency(*args, **kwargs) -> dict:
    """Bench's ROS measurement: ros/bench_ros.py's, imported only when bench runs it."""
    from .ros.bench_ros import round_trip_latency

    return round_trip_latency(*args, **kwargs)


def _extensions():
    """
    Subcommands defined next to the code they drive.

    bench, bags, the suite, honest answers and calibration, natural instructions, mirror
    averaging, ShapeWorld's,
    robustness, explain, and the closed-loop demo, which needs rclpy (without it, every other
    subcommand still works).
    """
    from .data import bags
    from .shapeworld import commands as shapeworld
    from .studies import (
        bench,
        calibration,
        explain,
        ground,
        honesty,
        kinds_ablation,
        mirror,
        natural,
        robustness,
        suite,
    )

    found = [
        functools.partial(bench.register_cli, ros_latency=ros_round_trip_latency),
        bags.register_cli,
        suite.register_cli,
        ground.register_cli,
        honesty.register_cli,
        natural.register_cli,
        mirror.register_cli,
        kinds_ablation.register_cli,
        calibration.register_cli,
        shapeworld.register_cli,
        robustness.register_cli,
        explain.register_cli,
    ]
    try:
        from .ros import demo
    except ImportError:
        return found
    return found + [demo.register_cli]


def main(argv: list[str] | None = None) -> int:
    keep_freed_memory()  # before any tensor: a training step's tensors then reuse their memory
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except (ValueError, FileNotFoundError) as exc:
        print(f'spatial-grounding: error: {exc}', file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == '__main__':
    sys.exit(main())
