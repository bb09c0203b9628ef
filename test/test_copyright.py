# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

import pytest

pytest.importorskip(
    'ament_copyright',
    reason='ament_copyright is not installed: it has no PyPI release; on ROS 2 Jazzy it is the '
    'ros-jazzy-ament-copyright system package',
)

from ament_copyright.main import main  # noqa: E402,I100


@pytest.mark.copyright
@pytest.mark.linter
def test_copyright():
    rc = main(argv=['.', 'test'])
    assert rc == 0, 'Found errors'
