"""RL by fitted value iteration: the regression target follows the value convention, only
visited cells are regressed, a tiny run learns something, and --via-ros runs the same loop
through a real gridworld node process."""
import json

import numpy as np
import pytest
import torch

from spatial_grounding_ros import cli
from spatial_grounding_ros.checkpoints import load_checkpoint
from spatial_grounding_ros.augment import mirror
from spatial_grounding_ros.env import GridWorldEnv
from spatial_grounding_ros.generator import generate
from spatial_grounding_ros.rl import (RLConfig, ReplayBuffer, act, fitted_value_step, reproduce_rl,
                                        train_rl)
from spatial_grounding_ros.text import Vocabulary, tokenize


class ConstantMap(torch.nn.Module):
    """A 'model' whose predicted map is a fixed array (for checking the regression target)."""

    def __init__(self, values):
        super().__init__()
        self.values = torch.nn.Parameter(torch.as_tensor(values, dtype=torch.float32))

    def forward(self, grids, tokens):
        return self.values.expand(len(grids), -1, -1)


def test_act_is_greedy_over_the_predicted_map():
    values = np.zeros((5, 5))
    values[2, 3] = 1.0
    rng = np.random.default_rng(0)
    assert act(values, (2, 2), 0.0, rng) == 3  # right
    assert act(values, (1, 3), 0.0, rng) == 1  # down


def test_fitted_value_target_uses_own_reward_and_target_max():
    data = generate(1, seed=0)
    grid, text = data.grids[0], data.instructions[0]
    buffer = ReplayBuffer((10, 10))
    i = buffer.map_id(grid, text)
    buffer.add(i, (0, 0), 3, -1.0, (0, 1), False)     # entered a puddle cell
    buffer.add(i, (4, 4), 1, 3.0, (5, 4), True)       # entered the goal
    target_values = np.arange(100, dtype=np.float32).reshape(10, 10) / 100
    online = ConstantMap(np.zeros((10, 10)))
    target = ConstantMap(target_values)
    vocab = Vocabulary.build([text])
    opt = torch.optim.SGD(online.parameters(), lr=0.5)
    cfg = RLConfig(batch_maps=1, gamma=0.9, priority=0.0)
    fitted_value_step(online, {}, target, vocab, buffer, opt, cfg, np.random.default_rng(0))
    # loss = mean over the 2 visited cells of (pred - target)^2; SGD step lr 0.5 moves each
    # visited cell by 0.5 * 2 * (target - pred) / 2 = 0.5 * target, the rest not at all
    moved = online.values.detach().numpy()
    expected_puddle = -1.0 + 0.9 * max(target_values[1, 1], target_values[0, 0], target_values[0, 2],
                                       target_values[0, 1])
    assert moved[0, 1] == pytest.approx(0.5 * expected_puddle, abs=1e-5)
    assert moved[5, 4] == pytest.approx(0.5 * 3.0, abs=1e-5)  # terminal: no bootstrap
    untouched = np.ones((10, 10), bool)
    untouched[0, 1] = untouched[5, 4] = False
    assert np.all(moved[untouched] == 0)


def test_mirror_images_record_the_mirrored_worlds_rewards():
    """Random play on one map fills its three mirror images with exactly the rewards and
    goal of the mirrored world (augment.mirror), and swaps the instruction's directions."""
    data = generate(3, seed=4, mode="local")
    env = GridWorldEnv(data, step_limit=60, order="sequential")
    buffer = ReplayBuffer((10, 10), mirrors=True)
    rng = np.random.default_rng(0)
    for _ in range(3):
        obs, _ = env.reset()
        i = buffer.map_id(obs["grid"], obs["instruction"])
        done = False
        while not done:
            s = obs["agent"]
            obs, r, terminated, truncated, _ = env.step(int(rng.integers(4)))
            buffer.add(i, s, 0, r, obs["agent"], terminated)
            done = terminated or truncated
    assert buffer.n_observed == 3 and len(buffer.grids) == 12
    lr, ud = mirror(data, 2), mirror(data, 1)
    images = {"lr": lr, "ud": ud, "both": mirror(lr, 1)}
    for k in range(3):
        ids = [k * 4 + j for j in range(4)]
        for i, world_set in zip(ids, [data, images["lr"], images["ud"], images["both"]]):
            assert np.array_equal(buffer.grids[i], world_set.grids[k])
            assert buffer.instructions[i] == world_set.instructions[k] or i == ids[0]
            seen = buffer.visited[i]
            assert seen.sum() == buffer.visited[ids[0]].sum() > 0
            assert np.array_equal(buffer.reward[i][seen], world_set.rewards[k][seen])
            assert np.array_equal(buffer.terminal[i][seen], world_set.terminal[k][seen])
    if "left" in tokenize(data.instructions[0]):
        assert "right" in tokenize(buffer.instructions[1])


def test_tiny_run_learns_and_writes_a_checkpoint(tmp_path):
    train, test = generate(60, seed=1, mode="local"), generate(30, seed=2, mode="local")
    cfg = RLConfig(episodes=256, envs=64, updates_per_round=8, batch_maps=32, seed=0)
    path, summary = train_rl("generator-local", "t-cnn", "", tmp_path, cfg, train, test,
                             progress=False)
    assert summary["episodes"] == 256 and summary["maps_seen"] <= 60
    assert summary["transitions"] >= 256
    assert 0 <= summary["test"]["md"] <= 18 and np.isfinite(summary["test"]["pq"])
    loaded = load_checkpoint(path)
    assert loaded.name == "t-cnn" and loaded.header["training"].startswith("rl")


def test_rl_train_via_ros(tmp_path, capsys):
    code = cli.main(["rl-train", "--task", "generator-local", "--model", "t-cnn", "--via-ros",
                     "--episodes", "6", "--step-limit", "10", "--generated", "20",
                     "--out", str(tmp_path), "--quiet"])
    assert code == 0
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert summary["episodes"] == 6
    assert 6 <= summary["transitions"] <= 60
    assert (tmp_path / "rl_generator-local_t-cnn.pt").is_file()


def test_reproduce_rl_keeps_rows_of_earlier_runs(data_dir, tmp_path):
    """A run over some tasks replaces its own rows of rl.json and keeps the others."""
    earlier = {"task": "isi", "model": "t-cnn", "test": {"pq": 0.5, "md": 3.0, "mse": 1.0, "n": 1},
               "episodes": 1, "train_seconds": 1.0}
    (tmp_path / "rl.json").write_text(json.dumps({"results": [earlier]}))
    reproduce_rl(str(data_dir), str(tmp_path), tasks=("pw-local",), models=("t-cnn",),
                 scale=1e-4, jobs=1, checkpoints=str(tmp_path))
    rows = json.loads((tmp_path / "rl.json").read_text())["results"]
    assert [(r["task"], r["model"]) for r in rows] == [("pw-local", "t-cnn"), ("isi", "t-cnn")]
    assert rows[0]["episodes"] == 1 and rows[0]["test"]["n"] == 399
    table = (tmp_path / "rl.md").read_text()
    assert "| pw-local | t-cnn |" in table and "| isi | t-cnn | 0.50 | 0.74 |" in table
