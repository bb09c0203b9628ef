# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
A run in one place: every setting of a supervised training run, for a task and a model.

A run's settings are written in a few places: TrainConfig's defaults (here), and in
core/tasks.py the task's fields, its models' own fields (`Task.recipes[model]`), its model
options (`Task.model`) and the settings every task shares (SYNTHETIC_SIZES, LATE_FROM,
NOISE_SHARE). `recipe(task, model, tc)` reads them all and returns the run resolved (`Recipe`):
every TrainConfig field, every ModelConfig field and the generated worlds' map sizes.
train_supervised trains what it returns, `spatial-grounding train --show-config` prints it, and
the summary of a run (so each row of results/value_map.json) records it.

    spatial-grounding train --task pw --model t-rnet-attn --show-config
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace

from .options import check, option
from ..core import tasks
from ..core.entities import TABLES
from ..data.generator import MODES
from ..data.noise import MAX_K
from ..models.config import ModelConfig
from ..models.protocol import Capabilities
from ..models.registry import capabilities, model_kind
from ..models.trnet import TRNet

# ModelConfig fields the run's data sets, which a recipe read before the run leaves unset
FROM_DATA = {
    'vocab_size': "the words of the run's training instructions, counted as it starts",
    'name_words': 'with skip_absent_names: the words naming each kind, set once trained',
}


@dataclass
class TrainConfig:
    """
    Training hyper-parameters, each declared once: `train` makes its options of them.

    A field left at None takes the task's value (tasks.py). Adam at the paper's lr 1e-3; batch
    64, not the paper's 512: PW local has ~1400 training maps, so 512 gives 3 steps an epoch, and
    on a CPU budget the number of steps, not the batch, is what limits the fit.
    """

    epochs: int | None = option(None, "training epochs (default: the task's)", low=1)
    batch_size: int = option(64, 'examples per optimizer step', low=1)
    lr: float = option(1e-3, 'Adam learning rate at the start', low=0.0)
    lr_final: float = option(1e-4, 'learning rate at the end of the cosine decay', low=0.0)
    val_fraction: float = option(
        0.1, 'share of the training worlds held out for validation', low=0.01, high=0.9
    )
    attention_warmup: float | None = option(
        None,
        'share of epochs t-RNetAttn trains with (still uniform) attention off (default: the '
        "task's)",
        low=0.0,
        high=1.0,
    )
    synthetic: int | None = option(
        None,
        'generated PuddleWorld examples added to training, all families, mixed sizes (default: '
        "the task's)",
        low=0,
    )
    generator_mode: str | None = option(
        None,
        "the generated worlds' mix of families, training and validation (data/generator.py "
        "MODES; default: the task's)",
        choices=tuple(MODES),
    )
    world_instructions: bool | None = option(
        None, "add the training worlds' synthetic pickle instructions (default: the task's)"
    )
    mirrors: bool | None = option(
        None, "add mirrored copies of the human training examples (default: the task's)"
    )
    distractors: int | None = option(
        None,
        'up to this many distractor objects on free cells of each training map, of kinds whose '
        "embeddings are redrawn from N(0, 1) every step (0: none; default: the task's)",
        low=0,
        high=MAX_K,  # as many as the robustness study's unseen objects
    )
    text_noise: int | None = option(
        None,
        'up to this many noise words (unknown words, verbs, articles) at one position of half '
        "the training instructions, once the attention trains (0: none; default: the task's)",
        low=0,
        high=MAX_K,  # as many as the robustness study inserts
    )
    noise_names: bool | None = option(
        None,
        'the noise words also name kinds neither on the map nor in the instruction (a third of '
        "them), as the robustness study's text-noise does: the node's Grounder leaves such "
        "names out, the network alone reads them (default: the task's recipe's, or off)",
    )
    skip_unknown: bool | None = option(
        None,
        'the model reads past words outside its vocabulary (ModelConfig.skip_unknown), and the '
        "noise words are fillers and names alone (default: the task's recipe's, or off)",
    )
    skip_absent_names: bool | None = option(
        None,
        'once trained, the model reads a name of a kind its map lacks as an unknown word, past '
        'which --skip-unknown reads (ModelConfig.name_words): that landmark cannot be the one '
        "meant. Training reads its instructions as written (default: the task's recipe's, or "
        'off)',
    )
    noise_share: float | None = option(
        None,
        "share of the training instructions that get noise words (default: the task's recipe's, "
        f'or {tasks.NOISE_SHARE})',
        low=0.0,
        high=1.0,
    )
    late_row_col: int | None = option(
        None,
        'generated row-col worlds added to training for its last epochs only (from '
        '--late-from): row-col in the whole run cost the human global split (docs/landmarks.md) '
        "(default: the task's recipe's, or none)",
        low=0,
    )
    late_from: float | None = option(
        None,
        "share of epochs before the --late-row-col worlds join (default: the task's recipe's, "
        f'or {tasks.LATE_FROM})',
        low=0.0,
        high=1.0,
    )
    paraphrase: float | None = option(
        None,
        'share of the generated training instructions reworded as people word them '
        "(data/paraphrase.py; 0: none; default: the task's)",
        low=0.0,
        high=1.0,
    )
    goal_weight: float | None = option(
        None, "weight of the goal-cell cross-entropy beside the MSE (default: the task's)",
        low=0.0,
    )
    goal_scale: float = option(
        5.0, "the values times this are the goal cross-entropy's logits (at the start)",
        low=0.01,
    )
    learn_goal_scale: bool = option(False, "learn the goal logits' temperature")
    select: str | None = option(
        None, 'keep the epoch of the second half with the best validation PQ plus '
        'generated-validation HIT (ties: MSE), or the lowest MSE of all epochs (default: the '
        "task's)",
        choices=('pq', 'mse'),
    )
    paper_model: bool = option(
        False,
        "the paper's model, without the task's additions (tasks.py: axial views, far relation, "
        'instruction in the head)',
    )
    init: str | None = option(
        None,
        "start from this checkpoint's weights (a packaged name or a path; its config and "
        'vocabulary must be the ones this run builds): fine-tuning',
    )
    seed: int = option(0, 'seed of the weights, the split and the batches', low=0, high=2**32 - 1)
    threads: int = option(2, 'torch threads', low=1)

    def __post_init__(self):
        check(self)

    def for_task(self, task: str, model: str) -> 'TrainConfig':
        """
        Return this config with every field left at None set to `model`'s value on `task`.

        Its recipe's (Task.recipes[model]) where it has one, else the task's: only `init` stays
        None (no checkpoint to start from), and `generator_mode` on a task without one (ISI).
        """
        settings = tasks.task(task)
        own = settings.recipes.get(model, {})  # the model's fields over the task's
        return replace(
            self,
            **{
                f.name: own[f.name] if f.name in own else getattr(settings, f.name)
                for f in fields(self)
                if getattr(self, f.name) is None and (f.name in own or hasattr(settings, f.name))
            },
        )


def task_training_config(
    task: tasks.Task, model_name: str, supports: Capabilities, tc: TrainConfig
) -> TrainConfig:
    """
    Return `tc` completed with the task's values for a model that `supports` so much.

    A model without distractor rows trains without the task's distractors, and refuses them
    when they are asked for; a model that is no t-RNet refuses skip_absent_names.
    """
    if not supports.distractor_rows:  # its entity table has the kinds alone
        if tc.distractors:
            raise ValueError(
                f'{model_name} has no distractor kinds; train it with --distractors 0'
            )
        tc = replace(tc, distractors=0)
    tc = tc.for_task(task.name, model_name)
    # a mode given to a task without one (ISI) would generate PuddleWorld worlds for it
    if task.generator_mode is None and (tc.synthetic or tc.generator_mode or tc.late_row_col):
        raise ValueError(
            '--synthetic, --generator-mode and --late-row-col add generated PuddleWorld '
            f'worlds; task {task.name} is not PuddleWorld'
        )
    if tc.skip_absent_names and not issubclass(model_kind(model_name).cls, TRNet):
        raise ValueError(f'--skip-absent-names: {model_name} does not read it (t-RNet models do)')
    return tc


def model_options(
    task: tasks.Task, supports: Capabilities, tc: TrainConfig, given: dict
) -> dict:
    """Return the run's ModelConfig fields: the task's model options, as far as it supports."""
    options = {**({} if tc.paper_model else task.model), **given}
    if tc.distractors:
        options['distractor_kinds'] = tc.distractors
    if tc.skip_unknown:
        options['skip_unknown'] = True
    if not supports.far_relation:  # the far relation is a relation network's
        options.pop('far', None)
    return options


@dataclass(frozen=True)
class Recipe:
    """A training run resolved: its task, its model and every setting it trains with."""

    task: str
    model: str
    train: TrainConfig  # every field set (`init` None: trained from scratch)
    # the model's config, its sizes those of the task's entity table; FROM_DATA fields: None
    # until the run reads its data (train_supervised's summary records the run's own)
    model_config: ModelConfig
    # (map size, share) of the generated worlds, of --synthetic's and of --late-row-col's
    synthetic_sizes: tuple

    def to_dict(self) -> dict:
        """Return the recipe as JSON-ready groups: train, model_config and data."""
        return {
            'task': self.task,
            'model': self.model,
            'train': asdict(self.train),
            'model_config': self.model_config.to_dict(),
            'data': {'synthetic_sizes': [list(s) for s in self.synthetic_sizes]},
        }

    def lines(self) -> list[str]:
        """Return the recipe as `name = value` lines, grouped [train], [model] and [data]."""
        groups = self.to_dict()
        out = [f'# {self.task} {self.model}: the run resolved (training/recipe.py)']
        for title, key in (('train', 'train'), ('model', 'model_config'), ('data', 'data')):
            out += ['', f'[{title}]']
            for name, value in groups[key].items():
                before_data = key == 'model_config' and self.model_config.vocab_size is None
                note = f'  # {FROM_DATA[name]}' if before_data and name in FROM_DATA else ''
                out.append(f'{name} = {value!r}{note}' if isinstance(value, str) else
                           f'{name} = {value}{note}')
        return out


def recipe(
    task: str, model: str, tc: TrainConfig | None = None, **given_model_options
) -> Recipe:
    """
    Return the run of `model` on `task` resolved: every setting train_supervised trains with.

    `tc`'s fields left at None take the task's values for the model; `given_model_options`
    are ModelConfig fields over the task's. Raises ValueError for a task or a model it does
    not know, or settings the model or the task refuses.
    """
    settings, supports = tasks.task(task), capabilities(model)
    tc = task_training_config(settings, model, supports, tc or TrainConfig())
    table = TABLES[settings.data]
    cfg = ModelConfig(
        n_entities=len(table),
        vocab_size=None,
        embed_dim=table.embed_dim,
        **model_options(settings, supports, tc, given_model_options),
    )
    return Recipe(task, model, tc, cfg, tasks.SYNTHETIC_SIZES)
