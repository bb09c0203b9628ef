# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Size limits of the package's code: a module up to 500 lines, a function up to 100.

A module or function that is longer on purpose is named, with the reason, in the table of
CONTRIBUTING.md's "Size limits" section: `path/to/module.py` for a module,
`path/to/module.py::function` (or `::Class.method`) for a function. Each failure lists every
offender at once, longest first.
"""

import ast
from pathlib import Path
import re

REPO = Path(__file__).resolve().parents[1]
ROOT = REPO / 'spatial_grounding_ros'
MODULE_LINES = 500
FUNCTION_LINES = 100


def exceptions(text: str | None = None) -> dict[str, str]:
    """Return the named exceptions of CONTRIBUTING.md's size-limit table: name -> reason."""
    text = (REPO / 'CONTRIBUTING.md').read_text() if text is None else text
    section = text.split('## Size limits', 1)[1].split('\n## ', 1)[0]
    found = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip('|').split('|')]
        match = len(cells) >= 2 and re.fullmatch(r'`([^`]+)`', cells[0])
        if line.lstrip().startswith('|') and match:
            found[match[1]] = cells[-1]
    return found


def module_lengths() -> dict[str, int]:
    return {
        str(f.relative_to(REPO)): len(f.read_text().splitlines())
        for f in sorted(ROOT.rglob('*.py'))
    }


def function_lengths() -> dict[str, int]:
    """Return every function's and method's length in lines, decorators included."""
    found = {}
    for f in sorted(ROOT.rglob('*.py')):
        tree = ast.parse(f.read_text(), str(f))

        def visit(node, prefix):
            for child in ast.iter_child_nodes(node):
                if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    start = min([child.lineno] + [d.lineno for d in child.decorator_list])
                    name = f'{f.relative_to(REPO)}::{prefix}{child.name}'
                    found[name] = child.end_lineno - start + 1
                    visit(child, f'{prefix}{child.name}.')
                elif isinstance(child, ast.ClassDef):
                    visit(child, f'{prefix}{child.name}.')

        visit(tree, '')
    return found


def offenders(lengths: dict[str, int], limit: int) -> list[str]:
    allowed = exceptions()
    over = [(n, name) for name, n in lengths.items() if n > limit and name not in allowed]
    return [f'  {name}: {n} lines' for n, name in sorted(over, reverse=True)]


def test_the_exceptions_table_is_read():
    text = (
        '## Size limits\n\n| exception | why |\n| --- | --- |\n'
        '| `a/b.py` | generated |\n| `a/c.py::f` | one table |\n\n## License\n| `x.py` | no |\n'
    )
    assert exceptions(text) == {'a/b.py': 'generated', 'a/c.py::f': 'one table'}
    assert isinstance(exceptions(), dict)


def test_modules_within_the_limit():
    over = offenders(module_lengths(), MODULE_LINES)
    assert not over, (
        f'modules over {MODULE_LINES} lines (split them, or name them with the reason in '
        "CONTRIBUTING.md's Size limits table):\n" + '\n'.join(over)
    )


def test_functions_within_the_limit():
    over = offenders(function_lengths(), FUNCTION_LINES)
    assert not over, (
        f'functions over {FUNCTION_LINES} lines (split them, or name them with the reason in '
        "CONTRIBUTING.md's Size limits table):\n" + '\n'.join(over)
    )


def test_every_exception_is_still_needed():
    lengths = {**module_lengths(), **function_lengths()}
    stale = sorted(
        name
        for name in exceptions()
        if lengths.get(name, 0) <= (MODULE_LINES if '::' not in name else FUNCTION_LINES)
    )
    assert not stale, f'{stale} are within the limits (or gone): remove them from the table'
