# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
What both executables share.

Declared and checked parameters, a diagnostic that is also logged, and a main() that spins one node
and shuts down cleanly.

Start-up errors (a bad parameter value or type, checkpoint, entity table or params file) are
one line `<name>: error: ...` on stderr and exit status 1.
"""

from __future__ import annotations

from dataclasses import dataclass
import faulthandler
import gc
import math
import os
import sys
from typing import Callable, Iterable, NoReturn

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import (
    FloatingPointRange,
    IntegerRange,
    ParameterDescriptor,
    SetParametersResult,
)
import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.publisher import Publisher
from std_msgs.msg import Header

from ..core.allocator import keep_freed_memory
from ..training.options import range_problem, range_words

# Declared by rclpy itself on every node; never reported as unknown.
RCLPY_PARAMETERS = ('use_sim_time', 'start_type_description_service')
TYPE_NAMES = {bool: 'a bool', int: 'an integer', float: 'a double', str: 'a string'}


@dataclass(frozen=True)
class Param:
    """
    One parameter of a node.

    Its default (whose Python type is the parameter's type), what it means, and what values it
    takes. A range or choice is worded and checked by training/options.py, as the command-line
    options are, so a node and the CLI state the same rule the same way.
    """

    name: str
    default: bool | int | float | str
    description: str
    read_only: bool = False  # only start-up (or a params file) can set it
    low: float | None = None  # inclusive range of a number
    high: float | None = None
    choices: tuple[str, ...] = ()
    non_empty: bool = False  # a string that must not be empty

    @property
    def type(self) -> type:  # noqa: A003
        return type(self.default)

    def constraints(self) -> str:
        """Return the rule as words, for `ros2 param describe` and error messages."""
        if self.choices:
            return 'one of ' + ', '.join(self.choices)
        if self.non_empty:
            return 'not empty'
        return range_words(self.low, self.high)

    def descriptor(self) -> ParameterDescriptor:
        descriptor = ParameterDescriptor(
            name=self.name,
            type=Parameter.Type.from_parameter_value(self.default).value,
            description=self.description,
            read_only=self.read_only,
            additional_constraints=self.constraints(),
        )
        if self.type is int and self.low is not None:
            descriptor.integer_range = [
                IntegerRange(
                    from_value=int(self.low),
                    to_value=int(self.high if self.high is not None else 2**63 - 1),
                    step=0,
                )
            ]
        elif self.type is float and self.low is not None:
            descriptor.floating_point_range = [
                FloatingPointRange(
                    from_value=float(self.low),
                    to_value=float(self.high if self.high is not None else sys.float_info.max),
                    step=0.0,
                )
            ]
        return descriptor

    def problem(self, value) -> str | None:
        """Return what is wrong with `value` for this parameter, or None."""
        # bool is an int in Python: compare exact types
        if type(value) is not self.type:
            hint = ' (write 5.0, not 5)' if self.type is float and type(value) is int else ''
            return (
                f'must be {TYPE_NAMES[self.type]}{hint}, got '
                f'{TYPE_NAMES.get(type(value), type(value).__name__)} {value!r}'
            )
        reason = self.choices and range_problem(value, choices=self.choices)
        if reason:
            return reason
        if self.non_empty and not value.strip():
            return 'must not be empty'
        if self.type is float and not math.isfinite(value):
            return f'must be a finite number, got {value!r}'
        if self.type in (int, float):
            return range_problem(value, self.low, self.high)
        return None


def declare_parameters(node: Node, params: Iterable[Param]) -> None:
    """
    Declare `params` on `node` with descriptors and refuse bad values.

    At start-up a bad value or type from a params file or `-p` raises ValueError (one line,
    naming the parameter); later, `set_parameters` refuses it with the same reason (and
    rclpy refuses changes to read-only parameters). Names in the node's overrides that are
    not parameters of the node get a warning: a typo would otherwise be ignored silently.
    """
    params = {p.name: p for p in params}

    def on_set(changes: list[Parameter]) -> SetParametersResult:
        for change in changes:
            spec = params.get(change.name)
            problem = spec and spec.problem(change.value)
            if problem:
                return SetParametersResult(
                    successful=False, reason=f'parameter {change.name} {problem}'
                )
        return SetParametersResult(successful=True)

    node.add_on_set_parameters_callback(on_set)
    # rclpy keeps what --params-file, -p and parameter_overrides gave this node here; there
    # is no public accessor for the overrides of names that are never declared
    overrides = dict(node._parameter_overrides)
    for spec in params.values():
        if spec.name in overrides:
            problem = spec.problem(overrides[spec.name].value)
            if problem:
                raise ValueError(f'parameter {spec.name} {problem}')
        node.declare_parameter(spec.name, spec.default, spec.descriptor())
    unknown = sorted(set(overrides) - set(params) - set(RCLPY_PARAMETERS))
    if unknown:
        node.get_logger().warning(
            f'ignoring unknown parameter(s) {", ".join(unknown)} (from a params file or -p): '
            f'{node.get_name()} has {", ".join(params)}'
        )


def report(
    node: Node, publisher: Publisher, part: str, level: bytes, message: str, **values
) -> None:
    """
    Publish `message` as one DiagnosticStatus named `<node>: part`, and log it.

    OKs are per-message events (a map held, an instruction grounded), so they log at debug,
    as Nav2's per-cycle messages do: at info, rclpy's logger (which inspects the caller's frame)
    cost more than the grounding itself on a 10x10 map. The diagnostics topic carries each.
    """
    # one call site per severity: rclpy refuses to change a call site's severity
    if level == DiagnosticStatus.OK:
        node.get_logger().debug(message)
    elif level == DiagnosticStatus.WARN:
        node.get_logger().warning(message)
    else:
        node.get_logger().error(message)
    status = DiagnosticStatus(
        level=level,
        name=f'{node.get_fully_qualified_name()}: {part}',
        message=message,
        hardware_id='',
    )
    status.values = [KeyValue(key=k, value=str(v)) for k, v in values.items()]
    publisher.publish(
        DiagnosticArray(header=Header(stamp=node.get_clock().now().to_msg()), status=[status])
    )


def spin(make_node: Callable[[], Node], name: str, args: list[str] | None = None) -> NoReturn:
    """Make the node, spin it until Ctrl-C or shutdown, and exit: 1 after a start-up error."""
    # a crash in a C library (DDS, torch) then leaves a Python traceback in the log
    faulthandler.enable()
    keep_freed_memory()  # a large map's tensors reuse the last one's memory
    code = _run(make_node, name, args)
    # The node is destroyed and the context shut down (which also closes ROS logging). A normal
    # exit would now run torch's and Fast DDS's C++ static destructors, whose relative order is
    # undefined: now and then one hung for seconds or crashed (exit -11) after a clean Ctrl-C.
    # Nothing is left to release, so leave without them.
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def _run(make_node: Callable[[], Node], name: str, args: list[str] | None) -> int:
    try:
        rclpy.init(args=args)
    except RuntimeError as exc:  # rclpy's RCLError: a missing or malformed --params-file, ...
        print(f'{name}: error: {str(exc).splitlines()[0]}', file=sys.stderr)
        return 1
    node = None
    try:
        node = make_node()
        # the model (with autostart), torch and rclpy made their long-lived objects at start-up:
        # freezing them keeps the collector's full passes, which scan every tracked object, off
        # the callbacks' latency
        gc.collect()
        gc.freeze()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except (ValueError, FileNotFoundError) as exc:  # bad parameter, checkpoint, table, data
        print(f'{name}: error: {exc}', file=sys.stderr)
        return 1
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0
