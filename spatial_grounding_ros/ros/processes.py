# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""Node processes that the demo, the benchmark and `rl-train --via-ros` start, and stop."""

from __future__ import annotations

from pathlib import Path
import subprocess
import sys

MODULES = {
    'gridworld': 'gridworld_node',
    'grounder': 'grounder_node',
    'entity_mapper': 'entity_mapper_node',
}


def executable(name: str) -> list[str]:
    """Return the console script `name` next to this Python (a venv's bin), else `python -m`."""
    script = Path(sys.executable).parent / name
    if script.is_file():
        return [str(script)]
    return [sys.executable, '-m', f'spatial_grounding_ros.ros.{MODULES[name]}']


def stop_processes(*processes: subprocess.Popen, timeout: float = 10.0) -> None:
    """Ask node processes to exit (SIGTERM), then kill whichever is still up after `timeout`."""
    for p in processes:
        p.terminate()
    for p in processes:
        try:
            p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()
