# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Inference through TorchScript traces: one per input shape, made on first use.

Grounding a small map is mostly Python around many small tensor ops (the output network's some
60, a new instruction's text code some 50). A trace runs the same ops on the same parameters
without the Python: bit for bit the module as written, in about 60% of its time. Each shape
gets its own trace, since the Python choices a module makes (layouts, tiles, gradient maps, a
sentence's length) are its shape's.
"""

from __future__ import annotations

import collections
from typing import Callable
import warnings
import weakref

import torch
from torch import nn

# each owner's traces, the most recently used TRACES_KEPT; kept outside the modules so that a
# copy of one (copy.deepcopy: rl.py's target network) never runs on the original's weights
TRACES_KEPT = 32
_TRACES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def traced(owner: nn.Module, make: Callable[[], nn.Module], inputs: tuple, key: tuple = ()):
    """
    Return `make()(*inputs)`, run as `owner`'s trace of it for these inputs' shapes and `key`.

    A trace is recorded on first use (some 25 ms) from the module that `make` returns (owner
    itself, or a wrapper of it whose outputs are tensors); `key` holds whatever else fixes its
    Python choices. It runs without the JIT's optimising passes: those profile the first runs
    and re-run them (some 10 ms more), and optimise nothing on these CPU graphs, so a trace is
    the ops as recorded. It reads the module's own parameters, so an optimizer's in-place
    steps reach it.
    """
    traces = _TRACES.setdefault(owner, collections.OrderedDict())
    key = (*key, *((x.shape, x.dtype, x.device) for x in inputs))
    trace = traces.pop(key, None)
    if trace is None:
        with warnings.catch_warnings():
            # its Python choices are the shape's, as meant. torch calls tracing deprecated
            # for torch.export and torch.compile: an exported head ran slower than this one
            # (0.8 ms at 10x10), and compiling needs a C++ toolchain and seconds at run
            # time; the pinned torch traces
            warnings.simplefilter('ignore', torch.jit.TracerWarning)
            warnings.simplefilter('ignore', DeprecationWarning)
            trace = torch.jit.trace(make(), inputs, check_trace=False)
        if len(traces) >= TRACES_KEPT:
            traces.popitem(last=False)
    traces[key] = trace
    with torch.jit.optimized_execution(False):
        return trace(*inputs)


def traces_of(owner: nn.Module) -> int:
    """Return how many traces `owner` keeps."""
    return len(_TRACES.get(owner, ()))
