# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The navigation environment of the paper's RL task, a Gymnasium environment.

One episode = one example of a `GroundingSet` (a map, an instruction, and that example's
reward and terminal maps): the agent starts on a random non-terminal cell, moves with
world.ACTIONS (up, down, left, right; off the map it stays put) and receives the reward of
the cell it enters (-1 in a puddle or on another ISI block, +3 and the episode ends at the
goal, 0 elsewhere). The true value map is never part of the observation; `info` carries
the example index so that training code can look up the map and the instruction.

    env = GridWorldEnv(generate(100, seed=0))
    obs, info = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(3)   # right
    env.reset(options={'example': 4, 'start': (0, 0)})      # a chosen example and start cell

The gridworld ROS node wraps this class, and ros/gridworld_client.py serves the same
interface over its topics, so in-process and through-ROS runs see the same world.
"""

from __future__ import annotations

import gymnasium
from gymnasium import spaces
import numpy as np

from ..core import world
from ..data.datasets import DEFAULT_DATA, GroundingSet, load_task
from ..data.generator import generate

DEFAULT_STEP_LIMIT = 50
# Episode sources made by the generator (no data set needed); the rest are tasks.TASKS.
GENERATED = ('generator', 'generator-local', 'generator-global')


def observation_space(shape: tuple[int, int], n_entities: int, instructions) -> spaces.Dict:
    """
    Return the observation space: the entity grid, the instruction, the agent's (row, col).

    The instruction's characters and length are those of `instructions` (the episodes' own).
    """
    charset = ''.join(sorted(set(''.join(instructions)))) or ' '
    return spaces.Dict(
        {
            'grid': spaces.Box(0, n_entities - 1, shape=shape, dtype=np.int64),
            'instruction': spaces.Text(
                max_length=max(1, *(len(t) for t in instructions)), min_length=0, charset=charset
            ),
            'agent': spaces.Tuple((spaces.Discrete(shape[0]), spaces.Discrete(shape[1]))),
        }
    )


class GridWorldEnv(gymnasium.Env):
    """Episodes over the examples of `data`, in a random order (or a fixed `order`)."""

    metadata = {'render_modes': []}

    def __init__(
        self, data: GroundingSet, step_limit: int = DEFAULT_STEP_LIMIT, order: str = 'random'
    ):
        if len(data) == 0:
            raise ValueError('the environment needs at least one example')
        if step_limit < 1:
            raise ValueError(f'step limit must be at least 1, not {step_limit}')
        if order not in ('random', 'sequential'):
            raise ValueError(f'unknown episode order {order!r}; use random or sequential')
        self.data, self.step_limit, self.order = data, step_limit, order
        self.observation_space = observation_space(
            self.shape, len(data.entities), data.instructions
        )
        self.action_space = spaces.Discrete(len(world.ACTIONS))
        self.example = -1
        self.agent: tuple[int, int] = (0, 0)
        self.steps = 0
        self.total_reward = 0.0
        self.done = True

    @property
    def shape(self) -> tuple[int, int]:
        return tuple(self.data.grids.shape[1:])

    @property
    def grid(self) -> np.ndarray:
        return self.data.grids[self.example]

    @property
    def instruction(self) -> str:
        return self.data.instructions[self.example]

    @property
    def goal(self) -> tuple[int, int]:
        return tuple(int(x) for x in self.data.goals[self.example])

    def observation(self) -> dict:
        """Return the observation: a copy of the grid, never a view into the data set."""
        return {'grid': self.grid.copy(), 'instruction': self.instruction, 'agent': self.agent}

    def info(self) -> dict:
        return {
            'example': self.example,
            'steps': self.steps,
            'total_reward': self.total_reward,
            'world': self.data.worlds[self.example] if self.data.worlds else '',
        }

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[dict, dict]:
        """
        Start the next episode: a random example (or the next one in order), a random start.

        `seed` seeds the environment's RNG (`self.np_random`), as Gymnasium does. Options:
        `example` (that example's episode) and `start` (that (row, col) start cell).
        """
        super().reset(seed=seed)
        options = options or {}
        unknown = set(options) - {'example', 'start'}
        if unknown:
            raise ValueError(f'unknown reset option(s) {sorted(unknown)}; use example, start')
        example = options.get('example')
        if example is None:
            example = (
                int(self.np_random.integers(len(self.data)))
                if self.order == 'random'
                else (self.example + 1) % len(self.data)
            )
        if not 0 <= example < len(self.data):
            raise ValueError(f'example {example} is out of range 0..{len(self.data) - 1}')
        self.example = int(example)
        start = options.get('start')
        if start is None:
            free = np.flatnonzero(~self.data.terminal[self.example].reshape(-1))
            start = np.unravel_index(int(self.np_random.choice(free)), self.shape)
        start = (int(start[0]), int(start[1]))
        if not (0 <= start[0] < self.shape[0] and 0 <= start[1] < self.shape[1]):
            raise ValueError(f'start cell {start} is outside the {self.shape} map')
        self.agent, self.steps, self.total_reward, self.done = start, 0, 0.0, False
        return self.observation(), self.info()

    def step(self, action: int) -> tuple[dict, float, bool, bool, dict]:
        if self.done:
            raise RuntimeError('the episode is over: call reset() first')
        self.agent = world.step_cell(self.agent, int(action), self.shape)
        reward = float(self.data.rewards[self.example][self.agent])
        terminated = bool(self.data.terminal[self.example][self.agent])
        self.steps += 1
        self.total_reward += reward
        truncated = not terminated and self.steps >= self.step_limit
        self.done = terminated or truncated
        return self.observation(), reward, terminated, truncated, self.info()


def load_episodes(
    source: str,
    split: str = 'train',
    data_dir: str = DEFAULT_DATA,
    n: int = 100,
    seed: int = 0,
) -> GroundingSet:
    """
    Load episodes from a task split or from the generator.

    Episodes from a task split (`pw-local`, `pw-global`, `pw`, `isi`) or from the
    generator (`generator`, `generator-local`, `generator-global`; `generator` = mixed).
    """
    if source.startswith('generator'):
        mode = source.partition('-')[2] or 'mixed'
        return generate(n, seed=seed, mode=mode)
    return load_task(source, split, data_dir)
