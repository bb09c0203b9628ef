# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The entity mapper's geometry, without a node: SLAM cells to entity cells, landmarks to cells.

Landmarks come from a file (read_landmarks_file) or markers (marker_landmark, which checks each:
finite numbers, a sane size, a name); entity_info sizes the entity map, entity_cells fills it
from the SLAM map, footprint_cells places a landmark on it, kind_of names its kind.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from pathlib import Path

from nav_msgs.msg import MapMetaData
import numpy as np
from visualization_msgs.msg import Marker
import yaml

from ..core.map_geometry import origin_quaternion, rotate
from ..language.lexicon import Lexicon, phrase_words, singular

# marker types that place a landmark; the rest (arrows, lines, meshes) are not places
PLACE_TYPES = (Marker.CUBE, Marker.CYLINDER, Marker.TEXT_VIEW_FACING)
MAX_NAME_CHARS = 200  # a longer marker text names no landmark


@dataclass(frozen=True)
class Landmark:
    """A named place: its map-frame centre and footprint (0: one cell)."""

    name: str
    x: float
    y: float
    size_x: float = 0.0
    size_y: float = 0.0
    frame_id: str = ''  # empty: the map's frame


def entity_info(info: MapMetaData, cell_size: float) -> MapMetaData:
    """Return the entity map's meta data: the SLAM map's origin pose, `cell_size` cells over it."""
    out = MapMetaData()
    out.resolution = float(cell_size)
    # a message's resolution is a float32 (0.05 is 0.0500000007): tolerate its rounding
    out.width = max(1, math.ceil(info.width * info.resolution / cell_size - 1e-4))
    out.height = max(1, math.ceil(info.height * info.resolution / cell_size - 1e-4))
    out.origin = info.origin
    return out


def entity_cells(
    slam: np.ndarray, resolution: float, info: MapMetaData, kinds: tuple[int, int, int], thr: int
) -> np.ndarray:
    """
    Return the (height, width) kinds of the entity map, in OccupancyGrid order (row 0 at origin).

    `slam` is the SLAM map in the same order. Each SLAM cell belongs to the entity cell holding
    its centre; an entity cell with an occupied SLAM cell is `kinds` obstacle, one with more
    unknown than known cells unknown, else free. An entity cell smaller than a SLAM cell reads
    the SLAM cell under its own centre. `kinds` is (free, obstacle, unknown).
    """
    free, obstacle, unknown = kinds
    h, w = info.height, info.width
    ratio = resolution / info.resolution
    rows = np.minimum(((np.arange(slam.shape[0]) + 0.5) * ratio).astype(np.int64), h - 1)
    cols = np.minimum(((np.arange(slam.shape[1]) + 0.5) * ratio).astype(np.int64), w - 1)
    owner = (rows[:, None] * w + cols[None, :]).ravel()
    cells = slam.ravel()
    total = np.bincount(owner, minlength=h * w)
    occupied = np.bincount(owner, weights=cells >= thr, minlength=h * w) > 0
    unknowns = np.bincount(owner, weights=cells < 0, minlength=h * w)
    out = np.where(occupied, obstacle, np.where(2 * unknowns > total, unknown, free))
    empty = np.flatnonzero(total == 0)
    if empty.size:  # cells finer than the SLAM map: the SLAM cell under the centre
        r = np.minimum(((empty // w + 0.5) / ratio).astype(np.int64), slam.shape[0] - 1)
        c = np.minimum(((empty % w + 0.5) / ratio).astype(np.int64), slam.shape[1] - 1)
        under = slam[r, c]
        out[empty] = np.where(under >= thr, obstacle, np.where(under < 0, unknown, free))
    return out.reshape(h, w)


def footprint_cells(landmark: Landmark, info: MapMetaData) -> tuple[slice, slice] | None:
    """
    Return the (rows, cols) slices, OccupancyGrid order, of the cells a landmark covers.

    The cells whose centres lie in its footprint (axis-aligned with the grid), or the one cell
    under its centre when the footprint holds no cell centre; None when that is off the map.
    """
    p = info.origin.position
    inverse = origin_quaternion(info.origin) * np.array([-1, -1, -1, 1])
    lx, ly, _ = rotate(inverse, np.array([landmark.x - p.x, landmark.y - p.y, 0.0]))
    size = info.resolution
    spans = []
    axes = ((ly, landmark.size_y, info.height), (lx, landmark.size_x, info.width))
    for centre, extent, n in axes:
        first = math.ceil((centre - extent / 2) / size - 0.5 - 1e-9)
        last = math.floor((centre + extent / 2) / size - 0.5 + 1e-9)
        if extent <= 0 or last < first:
            first = last = math.floor(centre / size)
        first, last = max(first, 0), min(last, n - 1)
        if last < first:
            return None
        spans.append(slice(first, last + 1))
    return spans[0], spans[1]


def kind_of(lexicon: Lexicon, name: str) -> int | None:
    """Return the kind a landmark name (a name, alias, plural or one-edit typo) names, or None."""
    words = phrase_words(name)
    if not words:
        return None
    if len(words) == 1:
        return lexicon.word_kind(words[0])
    return lexicon.phrase_kind(words[:-1] + (singular(words[-1]),))


def read_landmarks_file(path: str | Path) -> list[Landmark]:
    """
    Read `landmarks: [{name, x, y, size}]` (size: metres, a number or [x, y]; omitted: one cell).

    An optional top-level `frame_id` applies to every landmark. ValueError says what is wrong.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f'{path}: landmarks file not found')
    data = yaml.safe_load(path.read_text()) or {}
    items = data.get('landmarks') if isinstance(data, dict) else None
    if not isinstance(items, list):
        raise ValueError(f'{path}: a landmarks file holds `landmarks:`, a list of {{name, x, y}}')
    frame = str(data.get('frame_id') or '')
    out = []
    for i, item in enumerate(items):
        try:
            size = item.get('size', 0.0)
            sx, sy = (size, size) if isinstance(size, (int, float)) else size
            landmark = Landmark(
                str(item['name']), float(item['x']), float(item['y']), float(sx), float(sy), frame
            )
        except (AttributeError, KeyError, TypeError, ValueError) as exc:
            raise ValueError(
                f'{path}: landmark {i} ({item!r}) needs name, x, y and may give size '
                f'(a number or [x, y]): {exc}'
            ) from exc
        if not all(map(math.isfinite, (landmark.x, landmark.y, landmark.size_x, landmark.size_y))):
            raise ValueError(f'{path}: landmark {i} ({item!r}) has a non-finite number')
        out.append(landmark)
    return out


def marker_landmark(marker: Marker, max_size: float) -> Landmark:
    """
    Return the landmark a marker places; ValueError naming the marker and what is wrong.

    Its position and orientation must be finite, its scale.x and scale.y finite, not negative
    and at most `max_size` metres, its name (text, or ns) at most MAX_NAME_CHARS characters.
    """
    name = marker.text.strip() or marker.ns
    label = f'marker {marker.ns!r}/{marker.id} ({name[:40]!r})'
    p, q, scale = marker.pose.position, marker.pose.orientation, marker.scale
    if not all(map(math.isfinite, (p.x, p.y, p.z, q.x, q.y, q.z, q.w))):
        raise ValueError(f'{label} has a non-finite pose ({p.x}, {p.y}, {p.z})')
    for axis, extent in (('x', scale.x), ('y', scale.y)):
        if not math.isfinite(extent) or extent < 0 or extent > max_size:
            raise ValueError(
                f'{label} has scale.{axis} {extent}: a footprint is 0 to '
                f'max_landmark_size={max_size:g} m'
            )
    if not name.strip() or len(name) > MAX_NAME_CHARS:
        raise ValueError(f'{label} needs a name (text or ns) of 1 to {MAX_NAME_CHARS} characters')
    return Landmark(name, p.x, p.y, scale.x, scale.y, marker.header.frame_id)
