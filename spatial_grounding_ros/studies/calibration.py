# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
How sure a grounding is: temperature scaling of the value map, fitted once per checkpoint.

A grounding's confidence is the softmax of its value map at a temperature T, read at the best
cell (Grounder.judge). T is fitted by the likelihood of the cell meant, on examples the
checkpoint never trained on: its task's held-out validation worlds (the split training carved
with the checkpoint's own seed) and generated worlds of every family at 10x10 and 32x32 (seed
11; the suite uses 0). `calibrate --write` stores T in the checkpoint's header, beside the
weights, which it leaves as they are.

    spatial-grounding calibrate --checkpoint pw_t-rnet-attn --write
"""

from __future__ import annotations

import numpy as np
from tqdm import tqdm

from ..core import world
from ..data.datasets import DEFAULT_DATA, load_task, split_by_world
from ..data.generator import FAMILIES, sample
from ..grounder import Grounder
from ..models.checkpoints import rewrite_header

CALIBRATION_SEED = 11
TEMPERATURES = np.exp(np.linspace(np.log(1e-3), np.log(10.0), 241))


def held_out_examples(grounder: Grounder, data_dir) -> list[tuple[np.ndarray, str, tuple]]:
    """Return the human examples the checkpoint's training held out for validation."""
    header = grounder.loaded.header
    train = load_task(header['task'], 'train', data_dir)
    fraction = header.get('train_config', {}).get('val_fraction', 0.1)
    _, val = split_by_world(train, fraction, header.get('seed', 0))
    goals = world.argmax_cells(val.values)
    return [(g, t, tuple(goal)) for g, t, goal in zip(val.grids, val.instructions, goals)]


def generated_examples(sizes=(10, 32), per_family: int = 30, seed: int = CALIBRATION_SEED):
    out = []
    for size in sizes:
        for family in FAMILIES:
            rng = np.random.default_rng([seed, size, FAMILIES.index(family)])
            out += [sample(rng, family, size) for _ in range(per_family)]
    return out


def goal_values(grounder: Grounder, examples, progress: bool = True):
    """Return each example's value map (as the Grounder makes it) and the index of its goal."""
    out = []
    for grid, text, goal in tqdm(examples, desc='calibration', disable=not progress):
        values = grounder.ground(grid, text).values
        out.append((values.reshape(-1).astype(np.float64), goal[0] * values.shape[1] + goal[1]))
    return out


def mean_nll(scored, temperature: float) -> float:
    total = 0.0
    for flat, goal in scored:
        x = flat / temperature
        x = x - x.max()
        total -= x[goal] - np.log(np.exp(x).sum())
    return total / len(scored)


def fit_temperature(scored) -> float:
    """Return the temperature of the least mean negative log-likelihood (a grid search)."""
    return float(min(TEMPERATURES, key=lambda t: mean_nll(scored, t)))


def expected_calibration_error(confidence, correct, bins: int = 10) -> float:
    """Return the gap between confidence and accuracy, averaged over equal-width bins."""
    confidence, correct = np.asarray(confidence, float), np.asarray(correct, float)
    which = np.minimum((confidence * bins).astype(int), bins - 1)
    return float(
        sum(
            (which == b).mean() * abs(confidence[which == b].mean() - correct[which == b].mean())
            for b in range(bins)
            if (which == b).any()
        )
    )


# fits of the temperature, each on the groundings the last one's makes (see calibrate)
CALIBRATION_ROUNDS = 4


def calibrate(checkpoint: str, data_dir=DEFAULT_DATA, write: bool = False, progress=True) -> dict:
    """
    Fit the checkpoint's temperature; with `write`, store it in its header.

    The temperature decides which maps the Grounder averages over their mirror images (its
    calibrated certainty), and those averages are what is fitted: from 1, each round fits the
    groundings the last round's temperature makes, until it stays (at most
    CALIBRATION_ROUNDS), so the fit does not depend on a temperature the header held.
    """
    grounder = Grounder.from_checkpoint(checkpoint)
    human = held_out_examples(grounder, data_dir)
    examples = human + generated_examples()
    temperature, fits = 1.0, []
    for _ in range(CALIBRATION_ROUNDS):
        grounder.temperature = temperature
        scored = goal_values(grounder, examples, progress)
        temperature = fit_temperature(scored)
        fits.append(temperature)
        if len(fits) > 1 and fits[-1] == fits[-2]:
            break
    result = {
        'temperature': temperature,
        'rounds': fits,
        'fitted_on': f'{len(human)} held-out {grounder.loaded.header["task"]} examples and '
        f'{len(scored) - len(human)} generated (seed {CALIBRATION_SEED}, 10x10 and 32x32)',
        'nll': float(mean_nll(scored, temperature)),
    }
    if write:
        result['path'] = str(rewrite_header(checkpoint, calibration=result))
    return result


def cmd_calibrate(args) -> int:
    result = calibrate(args.checkpoint, args.data, args.write, progress=True)
    print(f'temperature {result["temperature"]:.4g} (mean NLL {result["nll"]:.3f}), fitted on '
          f'{result["fitted_on"]}' + (f'; written to {result["path"]}' if args.write else ''))
    return 0


def register_cli(sub) -> None:
    p = sub.add_parser('calibrate', help="fit a checkpoint's confidence temperature")
    p.add_argument('--checkpoint', default='pw_t-rnet-attn')
    p.add_argument('--data', default=DEFAULT_DATA, help='the data sets (held-out examples)')
    p.add_argument('--write', action='store_true', help="store it in the checkpoint's header")
    p.set_defaults(func=cmd_calibrate)
