# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The package's import layers.

Every import statement of the package (at the top of a module or inside a function) is read
from the source: no module may import itself back through others, nothing imports cli.py (the
one top floor), only modules under ros/ import rclpy, so the core runs without ROS, and a module
imports only modules of its own floor or below (FLOORS), so each floor can be read, tested and
reused without the ones above it.
"""

import ast
from pathlib import Path

PACKAGE = 'spatial_grounding_ros'
ROOT = Path(__file__).resolve().parents[1] / PACKAGE


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT.parent).with_suffix('').parts
    return '.'.join(parts[:-1] if parts[-1] == '__init__' else parts)


def imports(path: Path) -> set[str]:
    """Return the absolute names of the modules `path` imports, wherever the statement is."""
    here = module_name(path)
    package = here if path.name == '__init__.py' else here.rpartition('.')[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ''
            if node.level:
                anchor = package.split('.')[: len(package.split('.')) - (node.level - 1)]
                base = '.'.join(anchor + ([node.module] if node.module else []))
            # `from ..core import world` imports the module spatial_grounding_ros.core.world
            found.update(
                f'{base}.{alias.name}' if f'{base}.{alias.name}' in MODULES else base
                for alias in node.names
            )
    return found


FILES = sorted(ROOT.rglob('*.py'))
MODULES = {module_name(f) for f in FILES}


def package_graph() -> dict[str, set[str]]:
    return {module_name(f): imports(f) & MODULES for f in FILES}


def test_the_parser_sees_the_known_imports():
    graph = package_graph()
    assert f'{PACKAGE}.core.world' in graph[f'{PACKAGE}.training.env']
    assert f'{PACKAGE}.data.datasets' in graph[f'{PACKAGE}.cli']
    assert f'{PACKAGE}.models.config' in graph[f'{PACKAGE}.models.trnet']
    assert f'{PACKAGE}.ros.convert' in graph[f'{PACKAGE}.ros.gridworld_node']


def find_cycle(graph: dict[str, set[str]]) -> list[str]:
    """Return one import cycle as a path (first module = last), or [] (depth-first search)."""
    done, stack = set(), []

    def visit(module):
        stack.append(module)
        for dep in sorted(graph[module] - {module}):
            if dep in stack:
                return stack[stack.index(dep):] + [dep]
            if dep not in done:
                cycle = visit(dep)
                if cycle:
                    return cycle
        done.add(stack.pop())
        return []

    for module in sorted(graph):
        cycle = [] if module in done else visit(module)
        if cycle:
            return cycle
    return []


def test_cycle_finder_finds_a_cycle():
    assert find_cycle({'a': {'b'}, 'b': {'c'}, 'c': {'a'}, 'd': {'a'}}) == ['a', 'b', 'c', 'a']
    assert find_cycle({'a': {'b', 'c'}, 'b': {'c'}, 'c': set()}) == []


def test_no_import_cycle():
    cycle = find_cycle(package_graph())
    assert not cycle, 'import cycle: ' + ' -> '.join(cycle)


def test_cli_is_the_top_floor():
    graph = package_graph()
    importers = sorted(m for m, deps in graph.items() if f'{PACKAGE}.cli' in deps)
    assert not importers, f'{importers} import cli; take what they need from a lower module'


def test_rclpy_only_under_ros():
    outside = sorted(
        module_name(f)
        for f in FILES
        if not module_name(f).startswith(f'{PACKAGE}.ros')
        and any(m.split('.')[0] in ('rclpy', 'rosidl_runtime_py') for m in imports(f))
    )
    assert not outside, f'{outside} import rclpy outside ros/'


# Lowest first; a module imports only modules of its own floor or below. studies/ and shapeworld/
# share a floor (neither imports the other). The package's own __init__ is empty: floor 0.
FLOORS = (
    ('core',),
    ('language',),
    ('models',),
    ('data',),
    ('training',),
    ('grounder',),
    ('studies', 'shapeworld'),
    ('ros',),
    ('cli',),
)
# Upward imports that are known and why, (importer, imported): reason; each must still exist
# (test_upward_exceptions_are_real). None: what a module needs from above is passed in by cli.py
# (bench's ROS round trip, for one).
UPWARD: dict[tuple[str, str], str] = {}


def floor(module: str) -> int:
    """Return the floor of a module of the package (its first folder, or file, under it)."""
    parts = module.split('.')
    if len(parts) == 1:
        return 0
    for level, names in enumerate(FLOORS):
        if parts[1] in names:
            return level
    raise AssertionError(f'{module} is on no floor: add its folder to FLOORS')


def upward_imports(graph: dict[str, set[str]]) -> set[tuple[str, str]]:
    return {
        (module, dep)
        for module, deps in graph.items()
        for dep in deps
        if floor(dep) > floor(module)
    }


def test_floor_finder_sees_an_upward_import():
    core, models = f'{PACKAGE}.core.world', f'{PACKAGE}.models.trnet'
    graph = {core: {models}, models: set()}
    assert upward_imports(graph) == {(core, models)}


def test_every_module_is_on_a_floor():
    for module in package_graph():
        floor(module)


def test_imports_go_down_the_floors():
    """Each module imports from its own floor or below: core < models < ... < ros < cli."""
    upward = sorted(upward_imports(package_graph()) - set(UPWARD))
    assert not upward, 'imports from a higher floor:\n' + '\n'.join(
        f'  {module} (floor {floor(module)}) imports {dep} (floor {floor(dep)})'
        for module, dep in upward
    )


def test_upward_exceptions_are_real():
    stale = sorted(set(UPWARD) - upward_imports(package_graph()))
    assert not stale, f'{stale} no longer import upward: remove them from UPWARD'
