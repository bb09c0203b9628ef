# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Every shipped checkpoint's outputs on a fixed set of inputs: a check for a restructuring.

Before a change that must not change behaviour, write them; after it, check them:

    .venv/bin/python tools/golden_values.py write /tmp/golden.npz
    .venv/bin/python tools/golden_values.py check /tmp/golden.npz   # max abs difference: 0.0

On one machine an unchanged behaviour gives 0 to the bit. The file is not kept in the
repository: it is the code's own output, and another CPU may order float sums otherwise.
"""

from pathlib import Path

import numpy as np
import torch

INSTRUCTIONS = [
    'reach cell two below the westernmost rock',
    'go to the closest star to the house',
    'move to the cell between the heart and the tree',
    'reach the cell three above the circle',
]
SIZES = (10, 16, 32)
STATEMENTS = ['a red square is above a green circle', 'a blue shape is left of a triangle']


def grid_checkpoints() -> list[str]:
    from spatial_grounding_ros.models.checkpoints import PACKAGED_DIR

    return sorted(p.stem for p in PACKAGED_DIR.glob('*.pt') if 'shapeworld' not in p.stem)


def shapeworld_checkpoints() -> list[str]:
    from spatial_grounding_ros.models.checkpoints import PACKAGED_DIR

    return sorted(p.stem for p in PACKAGED_DIR.glob('shapeworld_*.pt'))


def grid_inputs(n_entities: int, size: int) -> np.ndarray:
    """4 maps of one size, every kind of a table drawn at random (the same for every model)."""
    return np.random.default_rng([size, n_entities]).integers(0, n_entities, (4, size, size))


def grid_outputs(name: str) -> dict[str, np.ndarray]:
    """Value maps (full forward), and value maps and Z1 a map at a time (text code, ground)."""
    from spatial_grounding_ros.grounder import Grounder
    from spatial_grounding_ros.training.supervised import predict_maps

    grounder = Grounder.from_checkpoint(name)
    out = {}
    for size in SIZES:
        grids = grid_inputs(len(grounder.entities), size)
        out[f'{name}/forward/{size}'] = predict_maps(
            grounder.model, grounder.vocab, grids, INSTRUCTIONS
        )
        # the node's fast path, a map at a time: the text code, then ground
        values, z1 = [], []
        with torch.no_grad():
            for grid, text in zip(grids, INSTRUCTIONS):
                tokens = torch.as_tensor(grounder.vocab.encode_batch([text]))
                code = grounder.model.text_code(tokens)
                v, aux = grounder.model.ground(torch.as_tensor(grid)[None], code, return_aux=True)
                values.append(v[0].numpy())
                z1.append(aux['relation_map'][0].numpy())
        out[f'{name}/ground/{size}'] = np.stack(values)
        out[f'{name}/z1/{size}'] = np.stack(z1)
    return out


def shapeworld_outputs(name: str) -> dict[str, np.ndarray]:
    from spatial_grounding_ros.shapeworld.training import load, predict

    model, vocab, _ = load(name)
    images = np.random.default_rng(7).random((len(STATEMENTS), 64, 64, 3)).astype(np.float32)
    return {f'{name}/logits': np.asarray(predict(model, vocab, images, STATEMENTS))}


def all_outputs() -> dict[str, np.ndarray]:
    torch.set_num_threads(1)
    out = {}
    for name in grid_checkpoints():
        out.update(grid_outputs(name))
    for name in shapeworld_checkpoints():
        out.update(shapeworld_outputs(name))
    return out


def differences(path: Path) -> dict[str, float]:
    """Return the max abs difference per output between the file and the code as it is now."""
    with np.load(path) as golden:
        now = all_outputs()
        assert sorted(golden.files) == sorted(now), 'the checkpoints or inputs changed'
        return {k: float(np.abs(golden[k] - now[k]).max()) for k in golden.files}


if __name__ == '__main__':
    import sys

    if len(sys.argv) != 3 or sys.argv[1] not in ('write', 'check'):
        sys.exit('usage: golden_values.py write|check FILE.npz')
    path = Path(sys.argv[2])
    if sys.argv[1] == 'check':
        worst = max(differences(path).values())
        print(f'max abs difference over every output: {worst}')
        sys.exit(worst != 0)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **all_outputs())
    print(f'wrote {path}')
