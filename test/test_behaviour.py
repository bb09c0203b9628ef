# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
What the shipped default model answers.

Clear instructions on hand-made and generated worlds land on the cell they name. These fail, not
skip, when a model regresses: each rate's floor sits about four binomial standard deviations under
what the shipped `pw_t-rnet-attn` does over several hundred worlds (README, suite table), so a
retrained default of the same quality passes and a model that regresses fails.
"""

import numpy as np
import pytest
from spatial_grounding_ros.core.entities import PUDDLEWORLD
from spatial_grounding_ros.data.generator import (
    FAMILIES,
    FAMILY_OFFSETS,
    LOCAL_FAMILIES,
    sample,
)
from spatial_grounding_ros.grounder import Grounder
from spatial_grounding_ros.language.places import Landmark, Place, surface
from spatial_grounding_ros.studies import suite
import torch

E = PUDDLEWORLD.index
OFFSETS = [(o, f) for f, offsets in FAMILY_OFFSETS.items() for o in offsets if o != (0, 0)]


@pytest.fixture(scope='module', autouse=True)
def one_torch_thread():
    """
    Ground on one torch thread, the node's default `torch_threads`.

    Next to other busy processes more threads mostly wait for each other; the session's
    count is restored after the module.
    """
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


@pytest.fixture(scope='module')
def grounder():
    return Grounder.from_checkpoint()  # the node's default, pw_t-rnet-attn


def hand_made(size):
    """Grass, one puddle, a star, a circle, rocks and trees: every answer below is unique."""
    grid = np.zeros((size, size), dtype=np.int64)
    grid[1:3, size - 4:size - 2] = E('puddle')
    grid[3, 4] = E('star')
    grid[6, 2] = E('circle')
    for cell in [(0, 5), (size - 2, 6), (5, 0), (4, size - 3)]:  # north, south, west, east
        grid[cell] = E('rock')
    grid[8, 8] = grid[0, 6] = E('tree')
    return grid


@pytest.mark.parametrize('size', [10, 32])
@pytest.mark.parametrize(
    'text,goal',
    [
        ('reach cell two below star', (5, 4)),
        ('reach cell two above star', (1, 4)),
        ('reach cell two to the left of star', (3, 2)),
        ('reach cell to right of circle', (6, 3)),
        ('reach cell on top of circle', (5, 2)),
        ('reach cell to bottom left of star', (4, 3)),
        ('reach cell one to the left and two below star', (5, 3)),
        ('reach cell with circle', (6, 2)),
    ],
)
def test_offsets_from_a_unique_object(grounder, size, text, goal):
    assert grounder.ground(hand_made(size), text).goal == goal


@pytest.mark.parametrize('size', [10, 32])
def test_offsets_on_a_map_of_free_space_and_four_objects(grounder, size):
    """A robot's map is mostly free: no puddle, no rocks or trees, four landmarks."""
    grid = np.zeros((size, size), dtype=np.int64)
    landmarks = {'diamond': (4, 4), 'triangle': (1, size - 2), 'circle': (size - 3, 2)}
    for name, cell in {**landmarks, 'heart': (size - 1, size - 1)}.items():
        grid[cell] = E(name)
    wrong = []
    for name, (r, c) in landmarks.items():
        for offset, family in OFFSETS:
            goal = (r + offset[0], c + offset[1])
            if 0 <= goal[0] < size and 0 <= goal[1] < size and grid[goal] == 0:
                text = surface(Place('landmark', Landmark(name), offset))
                if grounder.ground(grid, text).goal != goal:
                    wrong.append(text)
    assert not wrong, wrong


@pytest.mark.parametrize('size', [10, 32])
def test_the_four_extremes_pick_the_right_rock(grounder, size):
    grid = hand_made(size)
    answers = {
        'northernmost': (0, 5),
        'southernmost': (size - 2, 6),
        'westernmost': (5, 0),
        'easternmost': (4, size - 3),
    }
    for word, cell in answers.items():
        assert grounder.ground(grid, f'reach {word} rock').goal == cell, word


# Minimum exact-goal rate per family on 200 fresh generated 10x10 worlds each (the suite's worlds,
# another seed than the docs' table), one map at a time through the Grounder. The shipped default,
# on these worlds (and over 600, these and two other seeds), when the network read every family
# whole: 1.0 on every local family and extreme (1.0), 0.995 on extreme-offset (0.998), 1.0 on
# between (0.993), 0.93 on row-col (0.952) and 0.87 on closest (0.902), its weakest; closest and
# between are composed since (language/compose.py), 1.0. Each floor sits four or more binomial
# standard deviations (over 200 worlds) under the lowest of those rates: closest 0.77 (0.87 - 4 x
# 0.024), row-col 0.85 (0.93 - 4 x 0.018), between 0.93 (0.98, its lowest seed, - 4 x 0.010), and
# 0.95 where the default misses none (4 sd under a rate of 0.99). So a few argmax flips on another
# CPU, or a retrained default of the same quality, pass, and a model that regresses fails (the
# default before the far relation: 0.83 closest, 0.73 row-col; the one before the clear-references
# work: 0.0-0.37).
FLOOR = {
    **{f: 0.95 for f in LOCAL_FAMILIES},
    'extreme': 0.95,
    'closest': 0.77,
    'extreme-offset': 0.95,
    'row-col': 0.85,
    'between-one': 0.93,
}


def test_every_family_hits_on_generated_worlds():
    result = suite.run_suite('pw_t-rnet-attn', sizes=(10,), n=200, seed=123, progress=False)
    low = {f: v['10']['hit'] for f, v in result['families'].items() if v['10']['hit'] < FLOOR[f]}
    assert not low, f'families under their floor: {low}'


# Minimum exact-goal rate per family on 50 fresh generated 64x64 worlds each (sample(), one map
# at a time through the Grounder, as the node grounds). The shipped default over 400 such worlds
# per family (and the suite's 100 at 64x64): two-step and between 1.0 (1.0), extreme 0.995
# (0.98), row-col 0.94 (0.94; 0.915 the lower of two seeds), extreme-offset 0.93 (0.93),
# closest 0.75 (0.80). Each floor is at least four binomial standard deviations over 50 worlds
# under that rate, and at most 0.85: closest 0.50 (0.75 - 4 x 0.061), row-col 0.75 (0.915 -
# 4 x 0.039), extreme-offset 0.75 (0.93 - 4 x 0.037); 0.85 where the default misses (almost)
# none. Loose, so that a retrained default passes; a model that cannot ground at 64x64 (the
# default before the clear-references work: 0.0-0.37) fails.
FLOOR_64 = {
    'two-step': 0.85,
    'extreme': 0.85,
    'closest': 0.50,
    'extreme-offset': 0.75,
    'row-col': 0.75,
    'between-one': 0.85,
}
WORLDS_64 = 50


def test_families_hit_on_64x64_worlds(grounder):
    rates = {}
    for family in FLOOR_64:
        rng = np.random.default_rng([29, 64, FAMILIES.index(family)])
        worlds = [sample(rng, family, 64) for _ in range(WORLDS_64)]
        hits = [grounder.ground(grid, text).goal == tuple(goal) for grid, text, goal in worlds]
        rates[family] = float(np.mean(hits))
    low = {f: rate for f, rate in rates.items() if rate < FLOOR_64[f]}
    assert not low, f'families under their floor at 64x64: {low} (all: {rates})'


def worlds_with_an_object_beside_the_goal(n: int, steps: int, word: str, seed: int):
    """
    Yield (grid, instruction, goal) with an object beside the goal.

    "reach cell <steps> <word> <landmark>" on a 10x10 map of two objects, the second beside
    the goal across the offset's line.

    The suite's worlds seldom put an object there, and a retrained default can miss it where
    the suite's families do not move (the test below).
    """
    rng = np.random.default_rng(seed)
    kinds = [k for k in range(len(PUDDLEWORLD.names)) if k not in (0, *PUDDLEWORLD.obstacles)]
    dr, dc = DIRECTION_STEPS[word]
    made = 0
    while made < n:
        grid = np.zeros((10, 10), dtype=np.int64)
        first, second = rng.choice(kinds, 2, replace=False)
        r, c = (int(x) for x in rng.integers(0, 10, 2))
        goal = (r + steps * dr, c + steps * dc)
        beside = [(goal[0] + dc, goal[1] + dr), (goal[0] - dc, goal[1] - dr)][rng.integers(2)]
        if not all(0 <= x < 10 for x in (*goal, *beside)):
            continue
        grid[r, c], grid[beside] = first, second
        made += 1
        name = PUDDLEWORLD.names[first]
        yield grid, f'reach cell {NUMBER_WORDS[steps]} {word} {name}', goal


DIRECTION_STEPS = {'below': (1, 0), 'above': (-1, 0), 'to the left of': (0, -1),
                   'to the right of': (0, 1)}  # fmt: skip
NUMBER_WORDS = {1: 'one', 2: 'two', 3: 'three'}


# 80 worlds for each direction and count of cells, 960 in all. The shipped default hits 0.983
# of them (its weakest sets: three to the right 0.90, two above 0.94); the default retrained at
# dfdfb79 0.956 (three to the left 0.81, three to the right 0.84, two below 0.89). The floor
# sits five binomial standard deviations (over 960 worlds) under the shipped rate.
def test_an_object_beside_the_goal_does_not_move_it(grounder):
    rates = {
        (steps, word): np.mean(
            [
                grounder.ground(grid, text).goal == goal
                for grid, text, goal in worlds_with_an_object_beside_the_goal(
                    80, steps, word, seed=steps
                )
            ]
        )
        for word in DIRECTION_STEPS
        for steps in NUMBER_WORDS
    }
    assert np.mean(list(rates.values())) >= 0.96, rates
