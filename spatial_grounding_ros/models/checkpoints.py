# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Checkpoints: `torch.save` of {header, state_dict}, one writer and one reader for every model.

The header is plain data (model name, hyper-parameters, vocabulary, training data, metrics, and
a grid model's entity table), so loading works with `weights_only=True`, and any mismatch is a
clear error at load time, not a crash later. Two families share the format: the value-map
models of the grid tasks (`load_checkpoint`, here) and the ShapeWorld image classifiers, whose
header says task 'shapeworld' (their loader, shapeworld/training.py, needs their own models).
`read_checkpoint` refuses a checkpoint of the other family, so neither loader sees one.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import torch
from torch import nn

from .config import ModelConfig
from .encoders import EntityEncoder
from .registry import build_model, MODELS
from ..core.entities import EntityTable
from ..core.text import Vocabulary

FORMAT = 'spatial_grounding_ros/1'
PACKAGED_DIR = Path(__file__).resolve().parents[1] / 'checkpoints'  # the package's own
SHAPEWORLD = 'shapeworld'  # the header's task of a ShapeWorld image classifier
# what each family is, in the error that refuses one for the other
FAMILIES = {
    'grid': 'a value-map model (spatial-grounding eval)',
    SHAPEWORLD: 'a ShapeWorld image classifier (spatial-grounding shapeworld-eval)',
}


@dataclass
class Loaded:
    model: nn.Module
    vocab: Vocabulary
    entities: EntityTable
    header: dict

    @property
    def name(self) -> str:
        return self.header['model']


def write_checkpoint(
    path: str | Path, model_name: str, model: nn.Module, config: dict, vocab: Vocabulary, **info
) -> Path:
    """
    Write the package's checkpoint format: every checkpoint, of any model, is written here.

    `config` is the model's hyper-parameters as plain data (its `to_dict()`); `info` (task,
    entity table, training data, metrics, ...) goes into the header beside them.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    header = {
        'format': FORMAT,
        'model': model_name,
        'config': config,
        'vocabulary': list(vocab.words),
        **info,
    }
    return _write(path, header, model.state_dict())


def _write(path: Path, header: dict, state_dict: dict) -> Path:
    torch.save({'header': header, 'state_dict': state_dict}, path)
    return path


def rewrite_header(name: str | Path, **fields) -> Path:
    """Set header fields of a grid checkpoint (a calibration, say), its weights as they are."""
    path, header, state_dict = read_checkpoint(name, 'grid')
    return _write(path, {**header, **fields}, state_dict)


def save_checkpoint(
    path: str | Path,
    model_name: str,
    model: nn.Module,
    cfg: ModelConfig,
    vocab: Vocabulary,
    entities: EntityTable,
    **info,
) -> Path:
    """Write a grid model's checkpoint: its entity table goes into the header beside `info`."""
    return write_checkpoint(
        path, model_name, model, cfg.to_dict(), vocab, entities=entities.to_dict(), **info
    )


def resolve_checkpoint(name: str | Path) -> Path:
    """
    Resolve a path, or the name of a packaged checkpoint.

    Packaged names: `pw_t-rnet-attn` or `pw_t-rnet-attn.pt`.
    """
    path = Path(name)
    if path.is_file():
        return path
    packaged = PACKAGED_DIR / (path.name if path.suffix == '.pt' else f'{path.name}.pt')
    if packaged.is_file():
        return packaged
    raise FileNotFoundError(
        f'{name}: checkpoint not found (neither a file nor a packaged '
        f'checkpoint in {PACKAGED_DIR})'
    )


def family(header: dict) -> str:
    """Return the family of a checkpoint's header: 'shapeworld' or 'grid' (FAMILIES)."""
    return SHAPEWORLD if header.get('task') == SHAPEWORLD else 'grid'


def read_checkpoint(name: str | Path, expect_family: str) -> tuple[Path, dict, dict]:
    """
    Return (path, header, state_dict) of a checkpoint of `expect_family` ('grid', 'shapeworld').

    `name` is a path or a packaged name (resolve_checkpoint). A file torch cannot read, one
    without a header, another format, or a checkpoint of the other family is one ValueError
    line naming the file.
    """
    path = resolve_checkpoint(name)
    try:
        blob = torch.load(path, map_location='cpu', weights_only=True)
    except Exception as exc:  # torch raises many types on a corrupt or foreign file
        # torch's own text runs to several lines (and suggests weights_only=False): keep one
        reason = (str(exc).strip().splitlines() or [''])[0][:120]
        raise ValueError(
            f'{path}: not a readable checkpoint ({type(exc).__name__}: {reason})'
        ) from exc
    if not isinstance(blob, dict) or 'header' not in blob or 'state_dict' not in blob:
        raise ValueError(f'{path}: not a spatial_grounding_ros checkpoint (no header)')
    header = blob['header']
    if header.get('format') != FORMAT:
        raise ValueError(
            f'{path}: checkpoint format {header.get("format")!r}, expected {FORMAT!r}'
        )
    found = family(header)
    if found != expect_family:
        raise ValueError(f'{path}: holds {FAMILIES[found]}, not {FAMILIES[expect_family]}')
    return path, header, blob['state_dict']


def load_checkpoint(
    name: str | Path, expect_model: str | None = None, expect_entities: EntityTable | None = None
) -> Loaded:
    """
    Load a grid model (value maps) with its vocabulary, entity table and header.

    `expect_model` and `expect_entities` refuse a checkpoint of another model or entity table.
    A header written before models had unseen-kind rows gets them (EntityEncoder).
    """
    path, header, state_dict = read_checkpoint(name, 'grid')
    name_ = header.get('model')
    if name_ not in MODELS:
        raise ValueError(f'{path}: unknown model {name_!r} in checkpoint')
    if expect_model is not None and name_ != expect_model:
        raise ValueError(f'{path}: checkpoint holds model {name_!r}, not {expect_model!r}')
    entities = EntityTable.from_dict(header['entities'])
    if expect_entities is not None and entities.names != expect_entities.names:
        raise ValueError(
            f'{path}: checkpoint was trained on the {entities.domain} entity table '
            f'({len(entities)} kinds), not on {expect_entities.domain} '
            f'({len(expect_entities)} kinds)'
        )
    vocab = Vocabulary(header['vocabulary'][2:])
    try:
        cfg = ModelConfig.from_dict(header['config'])
    except (TypeError, ValueError) as exc:  # a field missing, or one this code does not know
        raise ValueError(f'{path}: {exc}') from exc
    if cfg.vocab_size != len(vocab) or cfg.n_entities != len(entities):
        raise ValueError(
            f'{path}: header sizes disagree (vocabulary {len(vocab)} vs '
            f'{cfg.vocab_size}, entities {len(entities)} vs {cfg.n_entities})'
        )
    state = state_dict
    if cfg.unseen_kinds < ModelConfig.unseen_kinds:
        # written before models had unseen-kind rows: give it the deterministic ones (models.py)
        cfg = replace(cfg, unseen_kinds=ModelConfig.unseen_kinds)
    model = build_model(name_, cfg)
    for prefix, module in model.named_modules():
        key = f'{prefix}.embed.weight'
        if isinstance(module, EntityEncoder) and key in state:
            state[key] = module.with_unseen_rows(state[key])
    try:
        model.load_state_dict(state)
    except RuntimeError as exc:
        first = str(exc).splitlines()[0]
        raise ValueError(f'{path}: weights do not fit model {name_!r}: {first}') from exc
    model.eval()
    return Loaded(model, vocab, entities, header)
