# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Point the ROS wheels' exported CMake files at this Python's include folders.

The PyPI wheels of the ROS 2 message packages were built on a manylinux image; their
exported CMake targets (share/<pkg>/cmake/*Export.cmake) name that machine's Python and numpy
include folders (/opt/python/cp311-cp311/...), which do not exist here, so find_package() of
a message package fails while building another interface package against the venv. This
rewrites them to the running interpreter's folders. Idempotent: a second run changes nothing.

    .venv/bin/python tools/fix_ros_wheels.py            # the prefix of the running venv
"""

from pathlib import Path
import sys
import sysconfig

import numpy

BUILD_ROOT = '/opt/python/cp311-cp311'
REPLACEMENTS = {
    f'{BUILD_ROOT}/include/python3.11': sysconfig.get_paths()['include'],
    f'{BUILD_ROOT}/lib/python3.11/site-packages/numpy/_core/include': numpy.get_include(),
}


def main() -> int:
    share = Path(sys.prefix) / 'share'
    changed = 0
    for path in share.glob('*/cmake/*.cmake'):
        text = path.read_text()
        if BUILD_ROOT not in text:
            continue
        for old, new in REPLACEMENTS.items():
            text = text.replace(old, new)
        path.write_text(text)
        changed += 1
    print(f'fix_ros_wheels: {changed} CMake file(s) rewritten under {share}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
