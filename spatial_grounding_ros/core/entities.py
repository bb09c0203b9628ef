# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Entity tables: what each integer in a grid means, per domain.

A grid cell holds an entity index; the model embeds that index. The ROS layer reads the
same tables from `config/entities_*.yaml`, so a data-set map can be published as-is.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

# PuddleWorld (Janner et al.): the indices of the data set's `map` arrays.
PUDDLEWORLD_NAMES = (
    'grass',
    'puddle',
    'star',
    'circle',
    'triangle',
    'heart',
    'spade',
    'diamond',
    'rock',
    'tree',
    'house',
    'horse',
)
PUDDLEWORLD_EMBED_DIM = 7  # the paper's size for PuddleWorld's kinds, and a table's default
PUDDLEWORLD_UNIQUE = ('star', 'circle', 'triangle', 'heart', 'spade', 'diamond')
PUDDLEWORLD_NONUNIQUE = ('rock', 'tree', 'house', 'horse')

# ISI (Bisk et al.): blocks are identified by their list position and the board's
# decoration; logo names in upstream order (GroundedLanguage's logo set).
ISI_LOGOS = (
    'adidas',
    'bmw',
    'burger_king',
    'coca_cola',
    'esso',
    'heineken',
    'hp',
    'mcdonalds',
    'mercedes_benz',
    'nvidia',
    'pepsi',
    'shell',
    'sri',
    'starbucks',
    'stella_artois',
    'target',
    'texaco',
    'toyota',
    'twitter',
    'ups',
)
ISI_NAMES = (
    ('empty',) + tuple(f'logo_{n}' for n in ISI_LOGOS) + tuple(f'digit_{i}' for i in range(1, 21))
)

# How a robot relates to a kind (a table's `traversal`, docs/landmarks.md):
# - free: open ground (a floor, grass);
# - passable: a landmark a robot may cross and stop on (a rug, a doorway, PuddleWorld's objects);
# - costly: passable at a cost, and a goal may lie there (PuddleWorld's puddle);
# - solid: a landmark a robot cannot enter (furniture): never a goal cell; "go to" it means a
#   free cell beside it (language/approach.py);
# - impassable: never entered, never a goal (walls, unknown space).
# A kind a table does not list is impassable if it is one of its `obstacles`, free if it is its
# free kind (the first kind that is no obstacle), else passable: a table with no `traversal`
# means what it meant before the key existed.
TRAVERSALS = ('free', 'passable', 'costly', 'solid', 'impassable')
# the kinds the model marks as obstacle: a table's `obstacles` are exactly these
MODEL_OBSTACLE = ('costly', 'impassable')
# kinds that are never a goal cell, and kinds a robot cannot cross
NEVER_GOAL = BLOCKS_ROBOT = ('solid', 'impassable')
# the shipped tables whose traversal is not the unlisted default, for a table saved before the
# key existed (a checkpoint's header): its domain -> (its names, its traversal)
SHIPPED_TRAVERSAL = {'puddleworld': (PUDDLEWORLD_NAMES, {'grass': 'free', 'puddle': 'costly'})}


@dataclass(frozen=True)
class EntityTable:
    """
    Entity names, obstacles, what each kind is to a robot, and the paper's embedding size.

    A grid cell holds an index 0..n-1 into `names`; the kinds in `obstacles` have reward -1
    and are what the model marks as obstacle (a user's table: its kinds that become the
    model's puddle), and `embed_dim` is the size the paper embeds this domain's kinds at (only
    training on the table reads it: the shipped default reads a table of a user's own by
    role). `traversal` says per kind how a robot relates to it (TRAVERSALS); `obstacles` are
    its costly and impassable kinds, `never_goal` and `blocks_robot` its solid and impassable
    ones.
    """

    domain: str
    names: tuple[str, ...]
    obstacles: tuple[int, ...]
    embed_dim: int
    # other words for each kind, aligned with names ("fridge": ("refrigerator",)); a table
    # without any is (), so tables written before aliases existed compare equal
    aliases: tuple[tuple[str, ...], ...] = ()
    # whether a landmark may cover several cells, its touching cells of one kind being one
    # landmark (core/footprints.py); None: yes, but for PuddleWorld's one-cell objects
    footprints: bool | None = None
    # each kind's traversal (TRAVERSALS), aligned with names; () for a table that lists none:
    # then each kind takes the unlisted default (traversal_of)
    traversal: tuple[str, ...] = ()

    def __len__(self) -> int:
        return len(self.names)

    def index(self, name: str) -> int:
        return self.names.index(name)

    def aliases_of(self, kind: int) -> tuple[str, ...]:
        return self.aliases[kind] if self.aliases else ()

    @property
    def free_kind(self) -> int:
        """Return the table's free ground: its first kind that is no obstacle."""
        return next(k for k in range(len(self.names)) if k not in self.obstacles)

    def traversal_of(self, kind: int) -> str:
        """Return how a robot relates to a kind: one of TRAVERSALS."""
        if self.traversal:
            return self.traversal[kind]
        return unlisted_traversal(kind, self.obstacles, self.free_kind)

    def kinds_that_are(self, *traversals: str) -> frozenset[int]:
        """Return the kinds whose traversal is one of `traversals`."""
        return frozenset(k for k in range(len(self.names)) if self.traversal_of(k) in traversals)

    @property
    def solid(self) -> frozenset[int]:
        """Return the kinds a robot approaches and never enters (furniture)."""
        return self.kinds_that_are('solid')

    @property
    def never_goal(self) -> frozenset[int]:
        """Return the kinds no goal cell may be: solid and impassable."""
        return self.kinds_that_are(*NEVER_GOAL)

    @property
    def blocks_robot(self) -> frozenset[int]:
        """Return the kinds a robot cannot cross: solid and impassable."""
        return self.kinds_that_are(*BLOCKS_ROBOT)

    @property
    def has_footprints(self) -> bool:
        """Return whether the table's landmarks may cover several cells (`footprints`)."""
        return self.domain != 'puddleworld' if self.footprints is None else self.footprints

    def to_dict(self) -> dict:
        d = {
            'domain': self.domain,
            'names': list(self.names),
            'obstacles': list(self.obstacles),
            'embed_dim': self.embed_dim,
        }
        if any(self.aliases):
            d['aliases'] = {n: list(a) for n, a in zip(self.names, self.aliases) if a}
        if self.footprints is not None:
            d['footprints'] = self.footprints
        if self.traversal:
            d['traversal'] = dict(zip(self.names, self.traversal))
        return d

    @classmethod
    def from_dict(cls, d: dict, domain: str = 'custom') -> 'EntityTable':
        """
        Return a table from its mapping; `domain` and `embed_dim` may be left out.

        `obstacles` may be left out too when `traversal` is given: they are then its costly
        and impassable kinds, which they must be when both are given.
        """
        try:
            names = tuple(str(n) for n in d['names'])
            domain = str(d.get('domain') or domain)
            listed = listed_traversal(names, domain, d.get('traversal'))
            if 'obstacles' in d or listed is None:
                obstacles = tuple(int(i) for i in d['obstacles'])
            else:
                obstacles = tuple(sorted(names.index(n) for n, t in listed.items()
                                         if t in MODEL_OBSTACLE))
            table = cls(
                domain,
                names,
                obstacles,
                int(d.get('embed_dim', PUDDLEWORLD_EMBED_DIM)),
                aliases_by_kind(names, d.get('aliases') or {}),
                None if d.get('footprints') is None else bool(d['footprints']),
            )
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(
                f'entity table is malformed ({exc}); it needs names and obstacles (or a '
                'traversal), and may give aliases (name: [other words]), domain, embed_dim, '
                'footprints and traversal (name: free, passable, costly, solid or impassable)'
            ) from exc
        bad = [i for i in table.obstacles if not 0 <= i < len(names)]
        if bad:
            raise ValueError(
                f'entity table obstacles {bad} are not indices of its {len(names)} names'
            )
        if listed is None:
            return table
        traversal = tuple(
            listed.get(n) or unlisted_traversal(k, table.obstacles, table.free_kind)
            for k, n in enumerate(names)
        )
        wrong = [
            f'{n} is {t}'
            for k, (n, t) in enumerate(zip(names, traversal))
            if (t in MODEL_OBSTACLE) != (k in table.obstacles)
        ]
        if wrong:
            raise ValueError(
                'entity table obstacles (what the model marks as obstacle) must be its costly '
                f'and impassable kinds, but {", ".join(wrong)}'
            )
        return replace(table, traversal=traversal)

    @classmethod
    def from_yaml(cls, path: str | Path) -> 'EntityTable':
        import yaml

        path = Path(path)
        if not path.is_file():
            raise FileNotFoundError(f'{path}: entity table file not found')
        try:
            data = yaml.safe_load(path.read_text())
        except yaml.YAMLError as exc:
            raise ValueError(f'{path}: not valid YAML ({exc})') from exc
        if not isinstance(data, dict):
            raise ValueError(f'{path}: an entity table must be a mapping')
        return cls.from_dict(data, domain=path.stem)


def unlisted_traversal(kind: int, obstacles: tuple[int, ...], free_kind: int) -> str:
    """Return the traversal of a kind a table does not list (as the key's absence meant)."""
    return 'impassable' if kind in obstacles else 'free' if kind == free_kind else 'passable'


def listed_traversal(names: tuple[str, ...], domain: str, traversal) -> dict | None:
    """
    Return a table's `traversal` (name -> one of TRAVERSALS), checked, or None.

    A table that gives none is None, but for a shipped table saved before the key existed
    (SHIPPED_TRAVERSAL: its domain and names), which takes the shipped traversal.
    """
    if traversal is None:
        shipped = SHIPPED_TRAVERSAL.get(domain)
        return dict(shipped[1]) if shipped and shipped[0] == names else None
    if not isinstance(traversal, dict):
        got = type(traversal).__name__
        raise TypeError(f'traversal must map a name to how a robot relates to it, got {got}')
    unknown = sorted(set(map(str, traversal)) - set(names))
    if unknown:
        raise ValueError(f'traversal names {unknown}, which are not names of the table')
    bad = {str(n): t for n, t in traversal.items() if t not in TRAVERSALS}
    if bad:
        raise ValueError(f'traversal {bad}: each must be one of {", ".join(TRAVERSALS)}')
    return {str(n): str(t) for n, t in traversal.items()}


def aliases_by_kind(names: tuple[str, ...], aliases: dict) -> tuple[tuple[str, ...], ...]:
    """Return a table's aliases (name -> word or list of words) as a tuple aligned with names."""
    if not isinstance(aliases, dict):
        got = type(aliases).__name__
        raise TypeError(f'aliases must map a name to its other words, got {got}')
    unknown = sorted(set(map(str, aliases)) - set(names))
    if unknown:
        raise ValueError(f'aliases name {unknown}, which are not names of the table')
    out = []
    for name in names:
        words = aliases.get(name) or []
        words = [words] if isinstance(words, str) else list(words)
        if not all(isinstance(w, str) and w.strip() for w in words):
            raise ValueError(f'the aliases of {name!r} must be non-empty strings, got {words}')
        out.append(tuple(w.strip() for w in words))
    return tuple(out) if any(out) else ()


PUDDLEWORLD = EntityTable.from_dict(
    {'domain': 'puddleworld', 'names': PUDDLEWORLD_NAMES, 'obstacles': [1], 'embed_dim': 7}
)
ISI = EntityTable('isi', ISI_NAMES, tuple(range(1, len(ISI_NAMES))), 13)
TABLES = {'puddleworld': PUDDLEWORLD, 'isi': ISI}
