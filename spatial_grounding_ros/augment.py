"""Mirror augmentation: a map flipped left-right (or top-bottom), with the direction words of
its instruction swapped, is another correct example: the grid MDP is symmetric under both
flips, so the flipped value map is exactly the value map of the flipped world.

Human instructions use many spellings; the tables below cover every direction word that
occurs at least twice in PuddleWorld train (misspellings map to the right opposite). A word
the tables miss leaves that mirrored example mislabeled, so the tables err on completeness."""
from __future__ import annotations

import numpy as np

from .datasets import GroundingSet
from .text import tokenize


def _pairs(*pairs: tuple[str, str]) -> dict[str, str]:
    table = {}
    for a, b in pairs:
        table.setdefault(a, b)
        table.setdefault(b, a)
    return table


# Mirror columns: west <-> east. Misspellings map to the correct opposite.
SWAP_LEFT_RIGHT = _pairs(
    ("left", "right"), ("leftmost", "rightmost"), ("west", "east"), ("western", "eastern"),
    ("westernmost", "easternmost"), ("westmost", "eastmost"), ("eastermost", "westernmost"),
    ("eaternmost", "westernmost"), ("northwest", "northeast"), ("southwest", "southeast"),
    ("northwestern", "northeastern"), ("southwestern", "southeastern"),
    ("northwesternmost", "northeasternmost"), ("southwesternmost", "southeasternmost"),
    ("lefthand", "righthand"), ("westward", "eastward"), ("westermost", "easternmost"),
    ("eastenmost", "westernmost"), ("mosteastern", "mostwestern"), ("topright", "topleft"),
    ("bottomright", "bottomleft"))
# Mirror rows: north <-> south.
SWAP_UP_DOWN = _pairs(
    ("above", "below"), ("up", "down"), ("top", "bottom"), ("topmost", "bottommost"),
    ("upper", "lower"), ("uppermost", "lowermost"), ("highest", "lowest"), ("higher", "lower"),
    ("north", "south"), ("northern", "southern"), ("northernmost", "southernmost"),
    ("northmost", "southmost"), ("upmost", "downmost"), ("over", "under"),
    ("bellow", "above"), ("beneath", "above"), ("underneath", "above"), ("bottomost", "topmost"),
    ("southernest", "northernmost"), ("northwest", "southwest"), ("northeast", "southeast"),
    ("northwestern", "southwestern"), ("northeastern", "southeastern"),
    ("northeasternmost", "southeasternmost"), ("northwesternmost", "southwesternmost"),
    ("low", "high"), ("northest", "southernmost"), ("southermost", "northernmost"),
    ("underneeth", "above"), ("topright", "bottomright"), ("topleft", "bottomleft"))


def swap_words(text: str, table: dict[str, str]) -> str:
    """The instruction's tokens with each direction word replaced by its mirror image."""
    return " ".join(table.get(w, w) for w in tokenize(text))


def mirror(data: GroundingSet, axis: int) -> GroundingSet:
    """axis 2: left-right (columns), axis 1: top-bottom (rows)."""
    if axis not in (1, 2):
        raise ValueError(f"mirror axis must be 1 (rows) or 2 (columns), not {axis}")
    table = SWAP_LEFT_RIGHT if axis == 2 else SWAP_UP_DOWN

    def flip(a: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(np.flip(a, axis=axis))

    goals = data.goals.copy()
    size = data.grids.shape[axis]
    goals[:, axis - 1] = size - 1 - goals[:, axis - 1]
    return GroundingSet(f"{data.name} mirrored", data.entities, flip(data.grids),
                        [swap_words(t, table) for t in data.instructions], flip(data.values),
                        flip(data.rewards), flip(data.terminal), goals, list(data.worlds))


def with_mirrors(data: GroundingSet) -> GroundingSet:
    """The data set plus its left-right, top-bottom and both-ways mirror images (4x)."""
    lr = mirror(data, 2)
    return GroundingSet.concat(data.name, [data, lr, mirror(data, 1), mirror(lr, 1)])
