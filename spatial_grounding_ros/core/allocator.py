# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Keep freed memory in the process for the next tensor of its size.

glibc's malloc gives every block over 128 KB a mapping of its own and returns it to the
system on free. A training step makes and frees the same tensors of a few megabytes every
time, so each one's pages fault in again, zeroed by the kernel: keeping them makes a step in a
fresh process clearly faster. A whole training run gains less, as glibc raises its own
threshold once validation's large batches are freed, and so does grounding a large map (the
measured figures: docs/benchmarks.md, "Figures behind design choices in the code"). What is
kept is the process's own peak, which it reaches anyway.

Called once by `spatial-grounding` and by the node executables, before any tensor is made.
On a C library without mallopt (not glibc) nothing changes.
"""

from __future__ import annotations

import ctypes

# glibc's mallopt parameters (malloc.h)
M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
# blocks up to this size come from the heap, which keeps them once freed (glibc's largest)
MMAP_THRESHOLD = 32 << 20
# free memory at the heap's top goes back to the system only past this
TRIM_THRESHOLD = 256 << 20


def keep_freed_memory() -> bool:
    """Set malloc to keep freed blocks of up to 32 MB; return whether the C library took it."""
    try:
        mallopt = ctypes.CDLL(None).mallopt  # the process's own symbols: its C library's
    except (OSError, AttributeError):  # not a C library with mallopt
        return False
    return bool(
        mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD) and mallopt(M_TRIM_THRESHOLD, TRIM_THRESHOLD)
    )
