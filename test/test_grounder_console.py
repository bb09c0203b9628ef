# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The venv console script `grounder` with its packaged defaults.

The venv console script `grounder`, with its packaged defaults, answers real PuddleWorld
test maps with the goal the Python API (Grounder.ground) gives them; bad start-up input is one
error line and exit status 1.
"""

from pathlib import Path
import subprocess
import sys

import numpy as np
import pytest

pytest.importorskip('rclpy', reason='rclpy is not installed')

from grounder_helpers import (  # noqa: E402, I100
    interrupt,
    make_probe,
    PUDDLEWORLD_YAML as PW_YAML,
    unique_namespace,
)
from spatial_grounding_ros.data.datasets import load_task  # noqa: E402
from spatial_grounding_ros.grounder import DEFAULT_CHECKPOINT, Grounder  # noqa: E402
from spatial_grounding_ros.ros import convert  # noqa: E402

NAMESPACE = unique_namespace('console_test')


def test_console_grounder_answers_test_maps_like_the_python_api(data_dir, ros_context):
    exe = Path(sys.executable).parent / 'grounder'
    if not exe.is_file():
        pytest.skip(f'{exe} is not installed (pip install -e . makes it)')
    test = load_task('pw-local', 'test', data_dir)
    api = Grounder.from_checkpoint(DEFAULT_CHECKPOINT)
    # seven maps the API answers (a declined one sends no goal: test_grounder_node covers it)
    answered = [
        i for i in range(0, 399, 19) if api.ground(test.grids[i], test.instructions[i]).goal
    ]
    test = test.subset(np.array(answered[:7]))
    expected = [api.ground(g, t).goal for g, t in zip(test.grids, test.instructions)]
    process = subprocess.Popen(
        # PuddleWorld maps: the default table is the office one (the entity mapper's)
        [str(exe), '--ros-args', '-r', f'__ns:={NAMESPACE}', '-p', f'entity_table:={PW_YAML}'],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        graph = ros_context
        probe = graph.add(make_probe(graph.context, NAMESPACE, f'{NAMESPACE}/spatial_grounder'))
        assert graph.wait_for(lambda: probe.connected() or process.poll() is not None, timeout=45)
        assert process.poll() is None, process.stdout.read()
        for grid, text, cell in zip(test.grids, test.instructions, expected):
            # the map and the instruction travel on different topics: send the instruction
            # once the node says (OK diagnostic with the map's stamp) that it holds this map
            message = probe.publish_map(grid)
            assert graph.wait_for(lambda: probe.holds(message)), text
            before = probe.counts()
            probe.publish_instruction(text)
            assert graph.wait_for(lambda: probe.new('goals', before)), text
            position = probe.new('goals', before)[0].pose.position
            centre = convert.cell_centre(tuple(int(c) for c in cell), convert.map_info(grid.shape))
            assert (position.x, position.y) == pytest.approx(centre[:2]), text
    finally:
        returncode, output = interrupt(process)
    assert returncode == 0, output


def test_bad_start_up_input_is_one_error_line_and_exit_1(tmp_path):
    """
    Check a claim of the README.

    README: a bad checkpoint, entity table or parameter value or type stops the node at start-up
    with one line `grounder: error: ...` and exit status 1 (no traceback), naming the problem.
    """
    exe = Path(sys.executable).parent / 'grounder'
    if not exe.is_file():
        pytest.skip(f'{exe} is not installed (pip install -e . makes it)')
    corrupt = tmp_path / 'corrupt.pt'
    corrupt.write_bytes(b'\x00 not a checkpoint')
    cases = {  # parameter -> what the line must say
        f'checkpoint:={tmp_path / "missing.pt"}': 'missing.pt: checkpoint not found',
        f'checkpoint:={corrupt}': 'corrupt.pt: not a readable checkpoint',
        # a PuddleWorld model reads any table; a model of another domain only its own
        'checkpoint:=isi_t-rnet-attn': 'a model trained on the isi table reads only that table',
        'entity_table:=no_such_table.yaml': 'no_such_table.yaml: config file not found',
        # parameters are checked against their declared type and range before anything loads
        'max_cells:=abc': "parameter max_cells must be an integer, got a string 'abc'",
        'max_cells:=-5': 'parameter max_cells must be 1..16777216, got -5',
        'max_instruction_chars:=0': 'parameter max_instruction_chars must be 1..100000, got 0',
        'torch_threads:=-3': 'parameter torch_threads must be 0..1024, got -3',
        'value_map_encoding:=heat': 'parameter value_map_encoding must be one of display, cost',
        'reground_on_map_change:=1': 'parameter reground_on_map_change must be a bool, got an',
        "default_frame_id:=''": 'parameter default_frame_id must not be empty',
    }
    namespace = unique_namespace('start_up_test')
    processes = {
        p: subprocess.Popen(
            [str(exe), '--ros-args', '-r', f'__ns:={namespace}', '-p', p],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for p in cases
    }
    for parameter, needle in cases.items():
        # a hang guard: eleven processes import torch at once, slow on a busy machine
        out, err = processes[parameter].communicate(timeout=600)
        assert processes[parameter].returncode == 1, (parameter, err)
        assert err.splitlines() == [err.strip()] and err.startswith('grounder: error: '), err
        assert needle in err, (parameter, err)


def test_a_bad_params_file_is_one_line_of_ours_and_exit_1(tmp_path):
    """
    Check a claim of the README.

    README: a missing or malformed --params-file exits 1 with our one error line after rcl's own
    parse error, and no traceback.
    """
    exe = Path(sys.executable).parent / 'grounder'
    if not exe.is_file():
        pytest.skip(f'{exe} is not installed (pip install -e . makes it)')
    malformed = tmp_path / 'malformed.yaml'
    malformed.write_text('spatial_grounder: [unclosed\n')
    for path in (tmp_path / 'missing.yaml', malformed):
        result = subprocess.run(
            [str(exe), '--ros-args', '--params-file', str(path)],
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert result.returncode == 1, result.stderr
        assert 'Traceback' not in result.stderr
        ours = [line for line in result.stderr.splitlines() if '[rcl]' not in line]
        assert len(ours) == 1 and ours[0].startswith('grounder: error: '), result.stderr
        assert 'params file' in ours[0], result.stderr
