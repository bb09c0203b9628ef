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

from dataclasses import dataclass
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


@dataclass(frozen=True)
class EntityTable:
    """
    Entity names, obstacles and the paper's embedding size.

    A grid cell holds an index 0..n-1 into `names`; the kinds in `obstacles` have reward -1,
    and `embed_dim` is the size the paper embeds this domain's kinds at (only training on the
    table reads it: the shipped default reads a table of a user's own by role).
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
        return d

    @classmethod
    def from_dict(cls, d: dict, domain: str = 'custom') -> 'EntityTable':
        """Return a table from its mapping; `domain` and `embed_dim` may be left out."""
        try:
            names = tuple(str(n) for n in d['names'])
            table = cls(
                str(d.get('domain') or domain),
                names,
                tuple(int(i) for i in d['obstacles']),
                int(d.get('embed_dim', PUDDLEWORLD_EMBED_DIM)),
                aliases_by_kind(names, d.get('aliases') or {}),
                None if d.get('footprints') is None else bool(d['footprints']),
            )
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(
                f'entity table is malformed ({exc}); it needs names and obstacles, and may '
                'give aliases (name: [other words]), domain, embed_dim and footprints'
            ) from exc
        bad = [i for i in table.obstacles if not 0 <= i < len(names)]
        if bad:
            raise ValueError(
                f'entity table obstacles {bad} are not indices of its {len(names)} names'
            )
        return table

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


PUDDLEWORLD = EntityTable('puddleworld', PUDDLEWORLD_NAMES, (1,), PUDDLEWORLD_EMBED_DIM)
ISI = EntityTable('isi', ISI_NAMES, tuple(range(1, len(ISI_NAMES))), 13)
TABLES = {'puddleworld': PUDDLEWORLD, 'isi': ISI}
