# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
ShapeWorld's subcommands: shapeworld-train, shapeworld-eval and reproduce-shapeworld.

They stand apart from the grid tasks' `train` and `eval`: the classifiers read images, not
entity grids, train with their own hyper-parameters (training.TrainConfig, one option per field)
and are scored by accuracy under image and text noise, not by value-map metrics.
"""

from __future__ import annotations

import json

from .data import ABSENT, load_split, SPLIT_SIZES
from .models import MODELS
from .reproduce import reproduce, REPRODUCED
from .training import accuracy, load, TASK, train, TrainConfig
from ..training import distributed
from ..training.options import add_options, from_options, ranged

CACHE_HELP = (
    'folder of the generated splits (default: $SPATIAL_GROUNDING_CACHE or '
    '~/.cache/spatial_grounding_ros)'
)


def cmd_train(args) -> int:
    if distributed.world_size() > 1:  # N copies would each train and write the same file
        raise ValueError('shapeworld-train trains in one process, not under torchrun')
    path, summary = train(args.model, args.out, from_options(TrainConfig, args), args.cache)
    print(json.dumps({'checkpoint': str(path), **summary}, indent=2))
    return 0


def cmd_eval(args) -> int:
    model, vocab, header = load(args.checkpoint)
    result = {
        'checkpoint': str(args.checkpoint),
        'model': header['model'],
        'task': TASK,
        'split': args.split,
        'image_noise': args.image_noise,
        'text_noise': args.text_noise,
        'seed': args.seed,
        'absent': args.absent,
        **accuracy(
            model,
            vocab,
            load_split(args.split, args.cache, absent=args.absent),
            args.image_noise,
            args.text_noise,
            args.seed,
        ),
    }
    if args.json:
        print(json.dumps(result))
    else:
        print(f'{header["model"]} on {TASK} {args.split} (n={result["n"]}): '
              f'ACC {result["acc"]:.3f}')
    return 0


def cmd_reproduce(args) -> int:
    reproduce(args.out, args.models, args.threads, args.epochs_scale, args.eval_only, args.cache)
    return 0


def register_cli(sub) -> None:
    """Add shapeworld-train, shapeworld-eval and reproduce-shapeworld to the subcommands."""
    t = sub.add_parser(
        'shapeworld-train',
        help='train a ShapeWorld classifier (t-RNetAttn on pixels, or t-VGG)',
        description='Train a ShapeWorld classifier on generated statements, keep the epoch of '
        'best validation accuracy, write <out>/shapeworld_<model>.pt. One process: under '
        'torchrun it is refused.',
    )
    t.add_argument('--model', required=True, choices=list(MODELS))
    t.add_argument('--out', default='out')
    t.add_argument('--cache', default=None, help=CACHE_HELP)
    add_options(t, TrainConfig)
    t.set_defaults(func=cmd_train)

    e = sub.add_parser('shapeworld-eval', help='accuracy of a ShapeWorld checkpoint on a split')
    e.add_argument('--checkpoint', required=True, help='a path or a packaged name')
    e.add_argument('--split', default='test', choices=list(SPLIT_SIZES))
    e.add_argument('--cache', default=None, help=CACHE_HELP)
    e.add_argument(
        '--image-noise', type=ranged(int, low=0), default=0, metavar='K',
        help='K patches of N(0, 1) pixels in each image, clear of the objects',
    )
    e.add_argument(
        '--text-noise', type=ranged(int, low=0), default=0, metavar='K',
        help='insert K verbs, articles and foreign object names at one position',
    )
    e.add_argument(
        '--absent', type=ranged(float, low=0.0, high=1.0), default=ABSENT, metavar='FRACTION',
        help="share of the split's false statements that name an absent object (default: the "
        "splits' mix; 0: every false statement plausible, the previous data)",
    )
    e.add_argument('--seed', type=int, default=0, help='seed of the noise')
    e.add_argument('--json', action='store_true', help='print exactly one JSON object')
    e.set_defaults(func=cmd_eval)

    r = sub.add_parser(
        'reproduce-shapeworld',
        help='train and evaluate t-VGG and t-RNetAttn on ShapeWorld, ship the checkpoints, '
        'write results/shapeworld.{json,md} and the noise table',
    )
    r.add_argument('--out', default='results')
    r.add_argument('--models', nargs='+', default=list(REPRODUCED), choices=list(MODELS))
    r.add_argument(
        '--threads', type=ranged(int, low=1), default=1, help='torch threads per training run'
    )
    r.add_argument(
        '--epochs-scale', type=ranged(float, low=0.001), default=1.0,
        help='multiply each epoch budget (e.g. 0.1 for a quick check)',
    )
    r.add_argument(
        '--eval-only', action='store_true', help='evaluate the shipped checkpoints, no training'
    )
    r.add_argument('--cache', default=None, help=CACHE_HELP)
    r.set_defaults(func=cmd_reproduce)
