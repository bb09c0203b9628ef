# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
A hyper-parameter dataclass is also its command-line options.

Each field is declared once, with `option(default, help, low=, high=, choices=)`: `add_options`
makes an argparse option of every field (`--batch-maps` for `batch_maps`, `--mirrors/--no-mirrors`
for a bool) with that default, help and range, and `from_options` builds the dataclass back from
the parsed arguments (`given_options`: only those given, when the rest has other defaults, such
as a task's). `ranged` range-checks an option that is no field. A dataclass that calls
`check(self)` in `__post_init__` refuses the same bad values from Python, so a default or a range
cannot differ between the API and the CLI. `range_words` and `range_problem` are the one
statement of an inclusive range and its error text: the ROS nodes' parameters
(ros/node_support.py) check theirs with them too.

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


def option(
    default,
    help: str,  # noqa: A002
    low: float | None = None,
    high: float | None = None,
    choices: tuple | None = None,
):
    """Declare a field: its default, what it means, its inclusive range or its choices."""
    return field(
        default=default, metadata={'help': help, 'low': low, 'high': high, 'choices': choices}
    )


def range_words(low: float | None, high: float | None) -> str:
    """Return an inclusive range as words: '1..5', 'at least 1', 'at most 5' or ''."""
    low, high = (
        None if x is None else str(x) if isinstance(x, int) else f'{x:g}' for x in (low, high)
    )
    if low is not None and high is not None:
        return f'{low}..{high}'
    if low is not None:
        return f'at least {low}'
    if high is not None:
        return f'at most {high}'
    return ''


def range_problem(
    value, low: float | None = None, high: float | None = None, choices: tuple | None = None
) -> str | None:
    """Return what is wrong with `value` for these choices or this inclusive range, or None."""
    if choices and value not in choices:
        return f'must be one of {", ".join(map(str, choices))}, got {value!r}'
    if (low is not None and value < low) or (high is not None and value > high):
        return f'must be {range_words(low, high)}, got {value!r}'
    return None


def constraint(f) -> str:
    """Return the field's range as words ('' when it has none)."""
    return range_words(f.metadata.get('low'), f.metadata.get('high'))


def problem(f, value) -> str | None:
    """Return what is wrong with `value` for field `f`, or None (None itself is always fine)."""
    if value is None or isinstance(value, bool):
        return None
    return range_problem(
        value, f.metadata.get('low'), f.metadata.get('high'), f.metadata.get('choices')
    )


def check(config) -> None:
    """Raise ValueError naming the first field of `config` whose value is out of range."""
    for f in fields(config):
        reason = problem(f, getattr(config, f.name))
        if reason:
            raise ValueError(f'{f.name} {reason}')


def ranged(kind, low: float | None = None, high: float | None = None):
    """
    Return an argparse `type` that parses `kind` and refuses values outside low..high.

    For options that are no dataclass field: `p.add_argument('--n', type=ranged(int, low=1))`.
    """
    return _parse_checked(kind, option(None, '', low=low, high=high))


def _parse_checked(kind, f):
    """Parse one command-line value of field `f` as `kind` and check its range."""

    def parse(text: str):
        value = kind(text)  # a ValueError here is argparse's "invalid int value: 'x'"
        reason = problem(f, value)
        if reason:
            raise argparse.ArgumentTypeError(reason)
        return value

    parse.__name__ = kind.__name__
    return parse


def add_options(
    parser: argparse.ArgumentParser, cls, skip: tuple[str, ...] = (), unset: bool = False
) -> None:
    """
    Add one option per field of dataclass `cls` (except `skip`) to `parser`.

    With `unset`, an option not given parses as None (the help still shows the field's
    default), so `given_options` can tell which were given.
    """
    hints = typing.get_type_hints(cls)
    for f in fields(cls):
        if f.name in skip:
            continue
        flag = '--' + f.name.replace('_', '-')
        hint = hints[f.name]
        kind = next((a for a in typing.get_args(hint) if a is not type(None)), hint)
        shown = '' if f.default is None else f'default: {f.default}'.replace('%', '%%')
        notes = '; '.join(n for n in (constraint(f), shown) if n)
        text = ' '.join(t for t in (f.metadata.get('help', ''), notes and f'({notes})') if t)
        default = None if unset else f.default
        if kind is bool:
            parser.add_argument(
                flag, action=argparse.BooleanOptionalAction, default=default, help=text
            )
        elif f.metadata.get('choices'):
            parser.add_argument(flag, choices=f.metadata['choices'], default=default, help=text)
        else:
            parser.add_argument(
                flag,
                type=_parse_checked(kind, f),
                default=default,
                metavar=kind.__name__.upper(),
                help=text,
            )


def given_options(cls, args: argparse.Namespace) -> dict:
    """Return the fields of `cls` whose options were given (added with `unset`)."""
    return {
        f.name: getattr(args, f.name)
        for f in fields(cls)
        if getattr(args, f.name, None) is not None
    }


def from_options(cls, args: argparse.Namespace, **values):
    """Build dataclass `cls` from the parsed options of its fields (and `values`)."""
    given = {f.name: getattr(args, f.name) for f in fields(cls) if f.name not in values}
    return cls(**given, **values)
