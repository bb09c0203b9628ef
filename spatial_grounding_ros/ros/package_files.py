# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Find the package's config files wherever it is installed.

Order: a path that exists as given; the ament index share directory
(share/spatial_grounding_ros/config of a colcon install, when ament_index_python is
available and the package is on AMENT_PREFIX_PATH); the source tree (an editable install,
`pip install -e .`); the environment's share directory (a plain pip install of the wheel).
"""

from __future__ import annotations

from pathlib import Path
import sys

PACKAGE = 'spatial_grounding_ros'
SOURCE_ROOT = Path(__file__).resolve().parents[2]


def share_dirs() -> list[Path]:
    """Candidate share directories of the package, most specific first."""
    found = []
    try:
        from ament_index_python.packages import get_package_share_directory

        try:
            found.append(Path(get_package_share_directory(PACKAGE)))
        except (LookupError, OSError):  # not in the index, or AMENT_PREFIX_PATH unset
            pass
    except ImportError:
        pass
    found += [SOURCE_ROOT, Path(sys.prefix) / 'share' / PACKAGE]
    return found


def find_config(name: str | Path) -> Path:
    """
    `name` if it is an existing file, else config/<name> in the first share directory that has it.

    FileNotFoundError lists where it looked.
    """
    path = Path(name).expanduser()
    if path.is_file():
        return path
    candidates = [d / 'config' / path.name for d in share_dirs()]
    for candidate in candidates:
        if candidate.is_file():
            return candidate
    raise FileNotFoundError(
        f'{name}: config file not found (looked in {", ".join(str(c.parent) for c in candidates)})'
    )
