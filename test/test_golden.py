# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""Every shipped checkpoint still gives the outputs written before the package was reorganised."""

from golden_values import differences

# another CPU may order float sums otherwise; the machine that wrote the file gives 0
TOLERANCE = 1e-5


def test_every_shipped_checkpoint_gives_its_recorded_outputs():
    worst = {k: d for k, d in differences().items() if d > TOLERANCE}
    assert not worst, f'outputs moved: {worst}'
