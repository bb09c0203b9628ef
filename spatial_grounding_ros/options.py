# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
A hyper-parameter dataclass is also its command-line options.

Each field is declared once, with `option(default, help, low=, high=)`: `add_options` makes an
argparse option of every field (`--batch-maps` for `batch_maps`, `--mirrors/--no-mirrors` for a
bool) with that default, help and range, and `from_options` builds the dataclass back from the
parsed arguments. A dataclass that calls `check(self)` in `__post_init__` refuses the same bad
values from Python, so a default or a range cannot differ between the API and the CLI.

    @dataclass
    class Config:
        steps: int = option(100, 'optimizer steps', low=1)
        def __post_init__(self):
            check(self)

    add_options(parser, Config)
    cfg = from_options(Config, parser.parse_args())
"""

from __future__ import annotations

import argparse
from dataclasses import field, fields
import typing


def option(default, help: str, low: float | None = None, high: float | None = None):  # noqa: A002
    """Declare a field: its default, what it means, and its inclusive range (None: open)."""
    return field(default=default, metadata={'help': help, 'low': low, 'high': high})


def constraint(f) -> str:
    """Return the field's range as words ('' when it has none)."""
    low, high = (
        None if x is None else str(x) if isinstance(x, int) else f'{x:g}'
        for x in (f.metadata.get('low'), f.metadata.get('high'))
    )
    if low is not None and high is not None:
        return f'{low}..{high}'
    if low is not None:
        return f'at least {low}'
    if high is not None:
        return f'at most {high}'
    return ''


def problem(f, value) -> str | None:
    """Return what is wrong with `value` for field `f`, or None (None itself is always fine)."""
    if value is None or isinstance(value, bool):
        return None
    low, high = f.metadata.get('low'), f.metadata.get('high')
    if (low is not None and value < low) or (high is not None and value > high):
        return f'must be {constraint(f)}, got {value!r}'
    return None


def check(config) -> None:
    """Raise ValueError naming the first field of `config` whose value is out of range."""
    for f in fields(config):
        reason = problem(f, getattr(config, f.name))
        if reason:
            raise ValueError(f'{f.name} {reason}')


def _value_type(f, hint):
    """Parse and range-check one command-line value of field `f`."""
    kind = next((a for a in typing.get_args(hint) if a is not type(None)), hint)

    def parse(text: str):
        value = kind(text)  # a ValueError here is argparse's "invalid int value: 'x'"
        reason = problem(f, value)
        if reason:
            raise argparse.ArgumentTypeError(reason)
        return value

    parse.__name__ = kind.__name__
    return kind, parse


def add_options(parser: argparse.ArgumentParser, cls, skip: tuple[str, ...] = ()) -> None:
    """Add one option per field of dataclass `cls` (except `skip`) to `parser`."""
    hints = typing.get_type_hints(cls)
    for f in fields(cls):
        if f.name in skip:
            continue
        flag = '--' + f.name.replace('_', '-')
        kind, parse = _value_type(f, hints[f.name])
        notes = [constraint(f), '' if f.default is None else 'default: %(default)s']
        notes = '; '.join(n for n in notes if n)
        text = ' '.join(t for t in (f.metadata.get('help', ''), notes and f'({notes})') if t)
        if kind is bool:
            parser.add_argument(
                flag, action=argparse.BooleanOptionalAction, default=f.default, help=text
            )
        else:
            parser.add_argument(
                flag, type=parse, default=f.default, metavar=kind.__name__.upper(), help=text
            )


def from_options(cls, args: argparse.Namespace, **values):
    """Build dataclass `cls` from the parsed options of its fields (and `values`)."""
    given = {f.name: getattr(args, f.name) for f in fields(cls) if f.name not in values}
    return cls(**given, **values)
