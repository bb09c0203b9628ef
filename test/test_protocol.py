# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The model protocol: what each registered model declares it supports is what it has.

Training and augmentation ask a model's Capabilities, never its name: a model registered
under a new name with no distractor rows is refused distractors as t-UVFA is.
"""

from dataclasses import replace

import numpy as np
import pytest
from spatial_grounding_ros.data.augment import add_distractors
from spatial_grounding_ros.data.generator import generate
from spatial_grounding_ros.data.noise import MAX_K, require_unseen_rows
from spatial_grounding_ros.models import registry
from spatial_grounding_ros.models.baselines import TCNN
from spatial_grounding_ros.models.checkpoints import load_checkpoint
from spatial_grounding_ros.models.config import ModelConfig
from spatial_grounding_ros.models.protocol import (
    Capabilities,
    KernelCode,
    RelationCode,
    TextVectorCode,
)
from spatial_grounding_ros.models.registry import build_model, capabilities, ModelKind, MODELS
from spatial_grounding_ros.training.supervised import train_supervised, TrainConfig
import torch

EXPECTED = {
    't-rnet-attn': Capabilities(
        relation_attention=True, far_relation=True, unseen_rows=True, distractor_rows=True
    ),
    't-rnet': Capabilities(far_relation=True, unseen_rows=True, distractor_rows=True),
    't-cnn': Capabilities(unseen_rows=True, distractor_rows=True),
    't-uvfa': Capabilities(),
}
CODES = {
    't-rnet-attn': RelationCode,
    't-rnet': RelationCode,
    't-cnn': KernelCode,
    't-uvfa': TextVectorCode,
}


def test_every_registered_model_declares_its_capabilities():
    assert set(EXPECTED) == set(MODELS)


@pytest.mark.parametrize('name', list(MODELS))
def test_capabilities_answer_for_every_registered_model(name):
    """The class's declaration, asked by name, is the built model's and matches what it has."""
    declared = capabilities(name)
    assert declared == EXPECTED[name]
    model = build_model(name, ModelConfig(vocab_size=5, distractor_kinds=3))
    assert model.capabilities == declared
    # attention: the projection that scores words per pair, and the switch of the warm-up
    assert hasattr(model, 'attn') == declared.relation_attention
    assert getattr(model, 'attention_on', False) == declared.relation_attention
    # the far relation: a model that supports it builds it, with its learned cost
    if declared.far_relation:
        far = build_model(name, ModelConfig(vocab_size=5, far=True))
        assert far.head.inputs == 3 and hasattr(far, 'far_log_cost')
    # the entity table's extra rows: as many as the config asks, after the kinds
    if declared.unseen_rows:
        assert model.unseen_kinds() == list(range(13, 13 + MAX_K))
        require_unseen_rows(model, name)
    else:
        with pytest.raises(ValueError, match='no embedding rows for unseen kinds'):
            require_unseen_rows(model, name)
    if declared.distractor_rows:
        assert model.distractor_kinds() == list(range(13 + MAX_K, 16 + MAX_K))
        assert model.phi.embed.num_embeddings == 16 + MAX_K
    # and the text code is the model's own dataclass, which ground takes
    tokens = torch.tensor([[2, 3, 4]])
    with torch.no_grad():
        code = model.text_code(tokens)
        assert type(code) is CODES[name]
        grids = torch.randint(0, 12, (2, 5, 6))
        assert model.ground(grids, code).shape == (2, 5, 6)


def test_a_model_with_fewer_unseen_rows_than_the_noise_places_is_refused():
    model = build_model('t-cnn', ModelConfig(vocab_size=5, unseen_kinds=3, distractor_kinds=10))
    with pytest.raises(ValueError, match=f'needs {MAX_K} of them'):
        require_unseen_rows(model, 't-cnn')


class PlainCNN(TCNN):
    """t-CNN as a model that declares no distractor rows: only the protocol says so."""

    @staticmethod
    def supports() -> Capabilities:
        return replace(TCNN.supports(), distractor_rows=False)


def test_training_refuses_distractors_for_a_model_without_distractor_rows(tmp_path, monkeypatch):
    monkeypatch.setitem(MODELS, 'plain-cnn', ModelKind(PlainCNN))
    assert not registry.capabilities('plain-cnn').distractor_rows
    tc = TrainConfig(
        epochs=1, batch_size=16, synthetic=0, mirrors=False, world_instructions=False,
        goal_weight=0.0, threads=1,
    )
    data = generate(40, seed=3, mode='local')
    with pytest.raises(ValueError, match='plain-cnn has no distractor kinds'):
        train_supervised(
            'pw', 'plain-cnn', '', tmp_path, replace(tc, distractors=2), train_data=data,
            progress=False,
        )
    # the pw task's own distractors are left out for it, as for t-UVFA
    path, _ = train_supervised(
        'pw', 'plain-cnn', '', tmp_path, tc, train_data=data, progress=False
    )
    assert torch.load(path, weights_only=True)['header']['config']['distractor_kinds'] == 0
    # and augmentation asks the protocol too
    model = PlainCNN(ModelConfig(vocab_size=4, distractor_kinds=2))
    grids, goals = torch.from_numpy(data.grids), torch.from_numpy(data.goals)
    with pytest.raises(ValueError, match='PlainCNN has no distractor kinds'):
        add_distractors(model, grids, goals, 2, np.random.default_rng(0))


def test_a_shipped_checkpoint_answers_the_protocol():
    model = load_checkpoint('pw_t-rnet-attn').model
    assert model.capabilities == EXPECTED['t-rnet-attn']
    assert len(model.unseen_kinds()) == MAX_K
