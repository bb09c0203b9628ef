# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""The allocator setting `spatial-grounding` and the nodes start with."""

import platform
import subprocess
import sys

import pytest

# In a process of its own (the setting is process-wide and comes before the allocations): is a
# new 16 MB tensor in the heap, which keeps freed blocks, or in a mapping of its own, which free
# returns to the system?
SCRIPT = """
import sys
from spatial_grounding_ros.core.allocator import keep_freed_memory
import torch
if sys.argv[1] == 'keep':
    assert keep_freed_memory()
tensor = torch.empty(4 << 20)
address = tensor.data_ptr()
for line in open('/proc/self/maps'):
    low, high = (int(a, 16) for a in line.split()[0].split('-'))
    if low <= address < high:
        print(line.split()[-1] if line.strip().endswith('[heap]') else 'own mapping')
"""


@pytest.mark.skipif(
    platform.system() != 'Linux' or platform.libc_ver()[0] != 'glibc', reason='glibc only'
)
def test_tensors_come_from_the_heap_that_keeps_freed_memory():
    """
    With the setting, a 16 MB tensor comes from the heap; without, from a mapping of its own.

    A training step makes and frees such tensors every time; a mapping of their own is returned
    on free and faults its pages in anew, zeroed, the next time.
    """
    where = {
        how: subprocess.run(
            [sys.executable, '-c', SCRIPT, how], capture_output=True, text=True, check=True
        ).stdout.strip()
        for how in ('keep', 'default')
    }
    assert where == {'keep': '[heap]', 'default': 'own mapping'}
