# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Goal navigation with RL (paper section 3.3).

Explore with the predicted value map, then fitted value iteration against a periodically synced
target network. Read top to bottom.

The agent never sees a true value map. It sees what an environment shows (the map, the
instruction, its cell) and the reward of each cell it enters. Value convention (world.py):
the value of a cell includes that cell's own reward, V(s) = R(s) + gamma * max_a V(next(s, a)),
and V(goal) = R(goal) at the terminal goal. A transition (s, a, r, s', done) therefore
teaches the value of s', the cell entered, whose reward r = R(s') it just observed:

    target(s') = r                                        if s' is terminal
    target(s') = r + gamma * max_a V_target(next(s', a))  otherwise

The "max over next cells" uses the known deterministic move model (world.next_cell_indices:
4 moves, off the map stays put), as in the paper's loss. Only cells the agent entered are
regressed. The regression is prioritized (RLConfig.priority): each visited cell's squared
error is weighted by (|error| + 0.1)^priority, so the few goal cells found, whose targets
stand out, are not drowned by the many wandering cells (plain mean square: priority 0).
Beside it, each map whose goal the agent has found (an observed terminal +reward cell) is
pointed at it by a cross-entropy over its cells (RLConfig.goal_weight): the regression alone
fits the goal's peak poorly, and the map's highest cell, which MD scores, lands off it. PQ
and MD are then measured on the predicted maps of the test split
(world.evaluate_maps), the true maps being used for that evaluation only.

train_rl takes any environments with GridWorldEnv's interface: `rl-train --via-ros` (cli.py)
runs the very same loop on the gridworld node's topics (ros/gridworld_client.py). The command
line and the paper's RL rows (reproduce.py) live outside this file.
"""

from __future__ import annotations

import copy
from dataclasses import asdict, dataclass, field, replace
import functools
from pathlib import Path
import time

import numpy as np
import torch

from .env import GridWorldEnv, load_episodes
from .options import check, option
from .supervised import predict
from ..core import world
from ..core.tasks import TASKS
from ..core.text import Vocabulary
from ..data.augment import mirror_cell, MIRROR_IMAGES, mirror_instruction
from ..data.datasets import GroundingSet
from ..models.checkpoints import save_checkpoint
from ..models.config import ModelConfig
from ..models.registry import build_model


@dataclass
class RLConfig:
    """All RL hyper-parameters, each declared once: `rl-train` makes its options of them."""

    episodes: int = option(16_000, 'episodes of experience in total', low=0)
    envs: int = option(128, 'episodes run side by side per round (one forward pass)', low=1)
    step_limit: int | None = option(
        None, "moves per episode before it is cut off (default: 5 * the map's longer side)", low=1
    )
    gamma: float = option(world.GAMMA, 'discount of the value targets', low=0.0, high=1.0)
    lr: float = option(1e-3, 'Adam learning rate', low=0.0)
    batch_maps: int = option(64, 'maps per regression step (all their visited cells)', low=1)
    updates_per_round: int = option(
        48, 'regression steps after each round of episodes', low=0
    )
    target_sync: int = option(100, 'regression steps between target-network syncs', low=1)
    priority: float = option(
        1.0, 'weight each cell by (|error| + 0.1)^priority (0: plain mean square)', low=0.0
    )
    goal_weight: float | None = option(
        None, 'weight of the cross-entropy toward the goal cells found in each map (0: none; '
        "default: the task's, tasks.py: 0.3 on PuddleWorld and generated worlds, 0 on ISI)", low=0
    )
    goal_scale: float = option(5.0, "values times this are that cross-entropy's logits", low=0.01)
    double: bool = option(
        False, 'double FVI: the online map picks the next cell, the target map values it'
    )
    eps_start: float = option(
        1.0, 'epsilon-greedy exploration at the start', low=0.0, high=1.0
    )
    eps_end: float = option(0.1, 'epsilon after the decay', low=0.0, high=1.0)
    eps_fraction: float = option(
        0.5, 'share of the episodes over which epsilon decays linearly', low=0.0, high=1.0
    )
    attention_warmup: float = option(
        0.85, 'share of episodes t-RNetAttn runs with (still uniform) attention off',
        low=0.0, high=1.0,
    )
    mirrors: bool | None = option(
        None, "also learn from the mirror images of each map (default: the task's, "
        'tasks.py: on for PuddleWorld and generated worlds)',
    )
    seed: int = option(0, 'seed of the weights, the exploration and the episodes', low=0,
                       high=2**32 - 1)
    threads: int = option(1, 'torch threads', low=1)

    def __post_init__(self):
        check(self)


class ReplayBuffer:
    """
    Transitions (map, instruction, s, a, r, s', done).

    Each distinct (map, instruction) pair is stored once and the transitions name it by id.
    Because moves are deterministic, the cells entered in a map, with
    their observed reward and terminal flag, are all a regression step needs: `visited`,
    `reward`, `terminal` (per map, (H, W)) are kept up to date from the transitions.

    With `mirrors`, each map also gets its three mirror images (direction words swapped),
    and every observed cell is recorded in them too: the flipped grid MDP has the flipped
    rewards, so the agent's own experience is reused four times without another step.
    """

    def __init__(self, shape: tuple[int, int], mirrors: bool = False):
        self.shape = shape
        self.mirrors = mirrors
        self.images: dict[int, list[tuple[int, tuple]]] = {}  # map id -> (mirror id, axes) each
        self.key_to_id: dict[tuple[bytes, str], int] = {}
        self.grids: list[np.ndarray] = []
        self.instructions: list[str] = []
        self.visited: list[np.ndarray] = []
        self.reward: list[np.ndarray] = []
        self.terminal: list[np.ndarray] = []
        self.transitions: list[tuple[int, int, int, float, int, bool]] = []

    def _new_map(self, grid: np.ndarray, instruction: str) -> int:
        self.grids.append(np.ascontiguousarray(grid, np.int64))
        self.instructions.append(instruction)
        for table, dtype in ((self.visited, bool), (self.reward, np.float32),
                             (self.terminal, bool)):
            table.append(np.zeros(self.shape, dtype))
        return len(self.grids) - 1

    def map_id(self, grid: np.ndarray, instruction: str) -> int:
        key = (np.asarray(grid, np.int64).tobytes(), instruction)
        if key not in self.key_to_id:
            i = self.key_to_id[key] = self._new_map(grid, instruction)
            self.images[i] = [
                (self._new_map(np.flip(grid, axis=axes), mirror_instruction(instruction, axes)),
                 axes)
                for axes in (MIRROR_IMAGES if self.mirrors else ())
            ]
        return self.key_to_id[key]

    @property
    def n_observed(self) -> int:
        """Count the maps the agent has played (not counting mirror images)."""
        return len(self.key_to_id)

    def add(self, map_id: int, s: tuple, a: int, r: float, s2: tuple, done: bool) -> None:
        w = self.shape[1]
        self.transitions.append((map_id, s[0] * w + s[1], a, r, s2[0] * w + s2[1], done))
        for i, axes in [(map_id, ()), *self.images[map_id]]:
            cell = mirror_cell(s2, self.shape, axes)
            self.visited[i][cell] = True
            self.reward[i][cell] = r
            self.terminal[i][cell] = done

    def sample_maps(self, rng: np.random.Generator, n: int) -> np.ndarray:
        return rng.choice(len(self.grids), size=min(n, len(self.grids)), replace=False)


@functools.lru_cache(maxsize=8)
def next_cells(height: int, width: int) -> np.ndarray:
    """world.next_cell_indices, computed once per map size (it is read at every step)."""
    return world.next_cell_indices(height, width)


def act(
    values: np.ndarray, cell: tuple[int, int], epsilon: float, rng: np.random.Generator
) -> int:
    """Epsilon-greedy over the greedy policy of a predicted value map."""
    if rng.random() < epsilon:
        return int(rng.integers(len(world.ACTIONS)))
    h, w = values.shape
    return int(values.reshape(-1)[next_cells(h, w)[cell[0] * w + cell[1]]].argmax())


@torch.no_grad()
def predicted_maps(
    model, vocab: Vocabulary, grids: list[np.ndarray], instructions: list[str]
) -> np.ndarray:
    model.eval()
    out = model(
        torch.as_tensor(np.stack(grids)), torch.as_tensor(vocab.encode_batch(instructions))
    )
    model.train()
    return out.numpy()


def run_episodes(
    envs: list,
    model,
    vocab: Vocabulary,
    buffer: ReplayBuffer,
    epsilon: float,
    rng: np.random.Generator,
    seeds: list[int | None] | None = None,
) -> list[float]:
    """
    One episode per environment, side by side, acting on one predicted map per episode.

    `seeds` go to the environments' reset (None: they go on with their own RNG). Returns each
    episode's total reward.
    """
    obs = [env.reset(seed=s)[0] for env, s in zip(envs, seeds or [None] * len(envs))]
    ids = [buffer.map_id(o['grid'], o['instruction']) for o in obs]
    maps = predicted_maps(model, vocab, [o['grid'] for o in obs], [o['instruction'] for o in obs])
    returns = [0.0] * len(envs)
    active = list(range(len(envs)))
    while active:
        still = []
        for i in active:
            s = obs[i]['agent']
            a = act(maps[i], s, epsilon, rng)
            obs[i], r, terminated, truncated, _ = envs[i].step(a)
            buffer.add(ids[i], s, a, r, obs[i]['agent'], terminated)
            returns[i] += r
            if not (terminated or truncated):
                still.append(i)
        active = still
    return returns


def goal_loss(pred: torch.Tensor, goals: torch.Tensor, scale: float) -> torch.Tensor:
    """Cross-entropy of the found `goals` (B, H*W) under softmax(scale * pred), maps with one."""
    found = goals.any(dim=1)
    if not found.any():
        return pred.new_zeros(())
    logits = scale * pred[found]
    on_goal = logits.masked_fill(~goals[found], float('-inf')).logsumexp(dim=1)
    return (logits.logsumexp(dim=1) - on_goal).mean()


def fitted_value_step(
    model,
    target_maps: dict,
    target_model,
    vocab: Vocabulary,
    buffer: ReplayBuffer,
    opt,
    cfg: RLConfig,
    rng: np.random.Generator,
) -> float:
    """One regression step on the visited cells of a batch of maps."""
    ids = buffer.sample_maps(rng, cfg.batch_maps)
    missing = [i for i in ids if i not in target_maps]
    if missing:  # the target network is fixed between syncs: compute each map once
        for i, v in zip(
            missing,
            predicted_maps(
                target_model,
                vocab,
                [buffer.grids[i] for i in missing],
                [buffer.instructions[i] for i in missing],
            ),
        ):
            target_maps[i] = v
    h, w = buffer.shape
    nxt = next_cells(h, w)  # (H*W, 4)
    grids = torch.as_tensor(np.stack([buffer.grids[i] for i in ids]))
    tokens = torch.as_tensor(vocab.encode_batch([buffer.instructions[i] for i in ids]))
    pred = model(grids, tokens).reshape(len(ids), -1)
    target_next = np.stack([target_maps[i].reshape(-1)[nxt] for i in ids])  # (B, H*W, 4)
    if cfg.double:  # the online map picks the next cell, the target map values it
        best = pred.detach().numpy()[:, nxt].argmax(axis=2)
        v_next = np.take_along_axis(target_next, best[..., None], axis=2)[..., 0]
    else:
        v_next = target_next.max(axis=2)
    reward = np.stack([buffer.reward[i].reshape(-1) for i in ids])
    terminal = np.stack([buffer.terminal[i].reshape(-1) for i in ids])
    visited = torch.as_tensor(np.stack([buffer.visited[i].reshape(-1) for i in ids]))
    target = torch.as_tensor(
        np.where(terminal, reward, reward + cfg.gamma * v_next), dtype=torch.float32
    )
    error = (pred - target)[visited]
    if cfg.priority > 0:  # prioritized regression: large errors (goals found) weigh more
        weight = (error.detach().abs() + 0.1) ** cfg.priority
        loss = (weight * error**2).sum() / weight.sum()
    else:
        loss = (error**2).mean()
    if cfg.goal_weight:  # the goal cells found in each map: observed terminal rewards above 0
        goals = torch.as_tensor(terminal & (reward > 0))
        loss = loss + cfg.goal_weight * goal_loss(pred, goals, cfg.goal_scale)
    opt.zero_grad()
    loss.backward()
    opt.step()
    return loss.item()


def make_envs(data: GroundingSet, cfg: RLConfig) -> tuple[list[GridWorldEnv], list[int]]:
    """
    Return `cfg.envs` environments and the seeds of their first reset.

    Environment n gets seed `cfg.seed + n * 2**32`, whose stream is that of
    np.random.default_rng([cfg.seed, n]) (the same SeedSequence entropy words).
    """
    envs = [GridWorldEnv(data, step_limit=cfg.step_limit) for _ in range(cfg.envs)]
    return envs, [cfg.seed + (n << 32) for n in range(cfg.envs)]


def resolve_config(cfg: RLConfig, task: str, shape: tuple[int, int]) -> RLConfig:
    """Fill in the options whose default depends on the task or the map size."""
    # generated worlds (not in TASKS) are PuddleWorld's kind: its defaults
    own = TASKS.get(task, TASKS['pw'])
    return replace(
        cfg,
        step_limit=cfg.step_limit or 5 * max(shape),
        mirrors=own.mirrors if cfg.mirrors is None else cfg.mirrors,
        goal_weight=own.rl_goal_weight if cfg.goal_weight is None else cfg.goal_weight,
    )


@dataclass
class Learner:
    """
    What fitted value iteration updates: the online and target networks and their data.

    `target_maps` caches the target network's predicted map of each buffer map until the next
    sync; `updates` counts the regression steps taken so far.
    """

    model: torch.nn.Module
    target_model: torch.nn.Module
    opt: torch.optim.Optimizer
    vocab: Vocabulary
    mcfg: ModelConfig
    cfg: RLConfig
    target_maps: dict = field(default_factory=dict)
    updates: int = 0

    @classmethod
    def build(cls, model_name: str, train: GroundingSet, cfg: RLConfig) -> Learner:
        """Build a fresh `model_name` (seeded by the caller) and its vocabulary of `train`."""
        # the mirror images' swapped direction words are trained on too
        vocab = Vocabulary.build(list(train.instructions) + [
            mirror_instruction(t, axes)
            for t in train.instructions if cfg.mirrors for axes in MIRROR_IMAGES
        ])
        mcfg = ModelConfig(
            n_entities=len(train.entities), vocab_size=len(vocab),
            embed_dim=train.entities.embed_dim,
        )
        model = build_model(model_name, mcfg)
        target_model = copy.deepcopy(model)
        opt = torch.optim.Adam(model.parameters(), lr=cfg.lr)
        return cls(model, target_model, opt, vocab, mcfg, cfg)

    def fit(self, buffer: ReplayBuffer, rng: np.random.Generator) -> list[float]:
        """Take one round of regression steps, syncing the target network on schedule."""
        losses = []
        for _ in range(self.cfg.updates_per_round):
            losses.append(
                fitted_value_step(
                    self.model, self.target_maps, self.target_model, self.vocab, buffer,
                    self.opt, self.cfg, rng,
                )
            )
            self.updates += 1
            if self.updates % self.cfg.target_sync == 0:
                self.target_model.load_state_dict(self.model.state_dict())
                self.target_maps.clear()
        return losses


def epsilon_at(cfg: RLConfig, episodes: int) -> float:
    """Exploration rate after `episodes` episodes: linear decay, then constant."""
    progress_frac = episodes / max(1, cfg.eps_fraction * cfg.episodes)
    return cfg.eps_start + min(1.0, progress_frac) * (cfg.eps_end - cfg.eps_start)


def run_rounds(
    learner: Learner,
    envs: list,
    seeds: list[int] | None,
    buffer: ReplayBuffer,
    rng: np.random.Generator,
    label: str | None,
) -> tuple[int, list[tuple[int, float, float, float]]]:
    """
    Alternate exploration and fitted value iteration until `cfg.episodes` episodes are run.

    Returns the episodes run and one log row per round: (episodes so far, mean return, mean
    loss, epsilon). With a `label`, every 20th round and the last are printed under it.
    """
    cfg, model = learner.cfg, learner.model
    episodes, log = 0, []
    start = time.perf_counter()
    warmup = (
        int(cfg.episodes * cfg.attention_warmup) if model.capabilities.relation_attention else 0
    )
    while episodes < cfg.episodes:
        # as in supervised training: attention weights start at 0, so until they switch on
        # t-RNetAttn is exactly t-RNet and the much cheaper attention-free forward is used
        if warmup:
            model.attention_on = learner.target_model.attention_on = episodes >= warmup
        # 1. explore with the current predicted maps
        epsilon = epsilon_at(cfg, episodes)
        batch = envs[: max(1, min(len(envs), cfg.episodes - episodes))]
        returns = run_episodes(batch, model, learner.vocab, buffer, epsilon, rng, seeds)
        seeds = None  # seeded once, at the first reset
        episodes += len(batch)
        # 2. fitted value iteration on the replay buffer
        losses = learner.fit(buffer, rng)
        log.append((episodes, float(np.mean(returns)), float(np.mean(losses)), epsilon))
        if label and (len(log) % 20 == 0 or episodes >= cfg.episodes):
            print(
                f'{label}: {episodes} episodes, '
                f'return {np.mean([row[1] for row in log[-20:]]):.2f}, '
                f'loss {np.mean([row[2] for row in log[-20:]]):.3f}, epsilon {epsilon:.2f}, '
                f'{time.perf_counter() - start:.0f} s',
                flush=True,
            )
    return episodes, log


def train_rl(
    task: str,
    model_name: str,
    data_dir: str | Path,
    out: str | Path,
    cfg: RLConfig = RLConfig(),
    train_data: GroundingSet | None = None,
    test_data: GroundingSet | None = None,
    envs: list | None = None,
    progress: bool = True,
) -> tuple[Path, dict]:
    """
    Train `model_name` by RL on `task`'s train split and evaluate it.

    The test split's metrics go into the returned summary and the checkpoint
    `out/rl_<task>_<model>.pt`, whose path is returned too. `train_data` and `test_data`
    replace the splits read from `data_dir`; `envs` replaces the in-process environments
    (the ROS client).
    """
    torch.manual_seed(cfg.seed)
    torch.set_num_threads(cfg.threads)
    rng = np.random.default_rng(cfg.seed)
    train = train_data if train_data is not None else load_episodes(task, 'train', str(data_dir))
    test = test_data if test_data is not None else load_episodes(task, 'test', str(data_dir))
    shape = tuple(train.grids.shape[1:])
    cfg = resolve_config(cfg, task, shape)
    learner = Learner.build(model_name, train, cfg)
    # environments given (the ROS client) are seeded by whoever made them
    envs, seeds = make_envs(train, cfg) if envs is None else (envs, None)
    buffer = ReplayBuffer(shape, cfg.mirrors)
    start = time.perf_counter()
    label = f'{task} {model_name}' if progress else None
    episodes, log = run_rounds(learner, envs, seeds, buffer, rng, label)
    train_seconds = time.perf_counter() - start
    # 3. evaluate the predicted maps of the test split (true maps used only here)
    model = learner.model
    metrics = world.evaluate_maps(
        predict(model, learner.vocab, test), test.values, test.rewards, test.terminal
    )
    summary = {
        'task': task,
        'model': model_name,
        'test': metrics,
        'episodes': episodes,
        'transitions': len(buffer.transitions),
        'maps_seen': buffer.n_observed,
        'updates': learner.updates,
        'train_seconds': round(train_seconds, 1),
        'rl_config': asdict(cfg),
    }
    path = save_checkpoint(
        Path(out) / f'rl_{task}_{model_name}.pt',
        model_name,
        model,
        learner.mcfg,
        learner.vocab,
        train.entities,
        task=task,
        training='rl (fitted value iteration)',
        training_data=f'{train.name} ({len(train)} examples, rewards only)',
        seed=cfg.seed,
        test_metrics=metrics,
        train_seconds=summary['train_seconds'],
        rl_config=asdict(cfg),
        return_history=[[e, round(r, 4), round(lo, 5)] for e, r, lo, _ in log],
    )
    return path, summary
