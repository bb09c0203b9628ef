# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
What the executables share.

Declared and checked parameters, a diagnostic that is also logged, a 1 Hz status on
/diagnostics (as diagnostic_updater publishes one), and a main() that spins one node and shuts
down cleanly. Public rclpy API only (test/test_rclpy_private.py checks it).

Start-up errors (a bad parameter value or type, checkpoint, entity table or params file) are
one line `<name>: error: ...` on stderr and exit status 1.
"""

from __future__ import annotations

from dataclasses import dataclass
import faulthandler
import functools
import gc
import math
import os
import sys
from typing import Callable, Iterable, NoReturn
import weakref

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from lifecycle_msgs.srv import ChangeState
from rcl_interfaces.msg import (
    FloatingPointRange,
    IntegerRange,
    ParameterDescriptor,
    SetParametersResult,
)
import rclpy
from rclpy.clock import Clock, ClockType
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.executors import ExternalShutdownException
from rclpy.lifecycle import LifecyclePublisher, TransitionCallbackReturn
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.publisher import Publisher
from rclpy.service import Service
from rclpy.subscription import Subscription
from rclpy.timer import Timer
from std_msgs.msg import Header

from .executors import make_executor
from ..core.allocator import keep_freed_memory
from ..core.topics import DIAGNOSTICS
from ..training.options import range_problem, range_words

# Declared by rclpy itself on every node; never reported as unknown.
RCLPY_PARAMETERS = ('use_sim_time', 'start_type_description_service')
# Give a node class this (as GrounderNode does; spin() passes it to the node it makes): the
# overrides from --params-file, -p and parameter_overrides are then declared parameters, the
# public way to see them, so a name the node does not have can be reported.
SEE_OVERRIDES = {'automatically_declare_parameters_from_overrides': True}
STEADY_TIME = ClockType.STEADY_TIME
STATUS_PERIOD = 1.0  # seconds between status diagnostics, as diagnostic_updater's default
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
    rclpy refuses changes to read-only parameters). A node made with SEE_OVERRIDES has its
    overrides declared already: names in them that are not parameters of the node get a
    warning (a typo would otherwise be ignored silently) and are undeclared again.
    """
    params = {p.name: p for p in params}
    refused = []  # on_set's reasons, for an override refused while declaring

    def on_set(changes: list[Parameter]) -> SetParametersResult:
        for change in changes:
            spec = params.get(change.name)
            problem = spec and spec.problem(change.value)
            if problem:
                refused.append(f'parameter {change.name} {problem}')
                return SetParametersResult(successful=False, reason=refused[-1])
        return SetParametersResult(successful=True)

    # declared from the overrides (SEE_OVERRIDES), or nothing but rclpy's own
    overrides = {
        name: node.get_parameter(name).value
        for name in node.list_parameters([], 0).names
        if name not in RCLPY_PARAMETERS
    }
    for spec in params.values():
        if spec.name in overrides:
            problem = spec.problem(overrides[spec.name])
            if problem:
                raise ValueError(f'parameter {spec.name} {problem}')
            node.undeclare_parameter(spec.name)  # declared again with its descriptor
    node.add_on_set_parameters_callback(on_set)
    for spec in params.values():
        try:
            node.declare_parameter(spec.name, spec.default, spec.descriptor())
        except (InvalidParameterValueException, InvalidParameterTypeException) as exc:
            # an override the node could not see (made without SEE_OVERRIDES): on_set's reason
            raise ValueError(refused[-1] if refused else f'parameter {spec.name}: {exc}') from None
    unknown = sorted(set(overrides) - set(params))
    for name in unknown:
        node.undeclare_parameter(name)
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
    if not publisher.get_subscription_count():  # volatile: no one would get it, so not built
        return
    status = DiagnosticStatus(
        level=level,
        name=f'{node.get_fully_qualified_name()}: {part}',
        message=message,
        hardware_id=node.get_fully_qualified_name(),  # as diagnostic_updater sets it
    )
    status.values = [KeyValue(key=k, value=str(v)) for k, v in values.items()]
    publisher.publish(
        DiagnosticArray(header=Header(stamp=node.get_clock().now().to_msg()), status=[status])
    )


def error_text(exc: Exception, plain: tuple[type, ...] = (ValueError,)) -> str:
    """Return an error's words: its message for the `plain` types, else with its type's name."""
    return str(exc) if isinstance(exc, plain) else f'{type(exc).__name__}: {exc}'


def guarded(part: str):
    """
    Decorate a node's callback so that no error ends the process.

    An error a callback did not expect becomes an ERROR diagnostic named `part` (through the
    node's report method) and the node keeps serving: rclpy's executor would re-raise it out of
    spin().
    """

    def wrap(method):
        @functools.wraps(method)
        def call(self, *args):
            try:
                return method(self, *args)
            except Exception as exc:  # noqa: BLE001 - the node must outlive any input
                try:
                    self.report(
                        part,
                        DiagnosticStatus.ERROR,
                        f'{part}: unexpected {type(exc).__name__}: {exc}; the input was '
                        'skipped, the node goes on',
                    )
                except Exception:  # noqa: BLE001, S110 - nothing is left to tell it with
                    pass
                return None

        return call

    return wrap


def autostart(node) -> None:
    """
    Configure and activate a lifecycle node at start-up, unless its `autostart` is false.

    A failed configure raises ValueError with the node's configure_error (main()'s one error
    line); with autostart false the node waits, unconfigured, for a lifecycle manager.
    """
    if not node.get_parameter('autostart').value:
        node.get_logger().info(
            f'unconfigured: waiting for a lifecycle manager on '
            f'{node.get_fully_qualified_name()}/change_state'
        )
        return
    node.autostarting = True  # a failed configure is then main()'s one error line
    try:
        if node.trigger_configure() != TransitionCallbackReturn.SUCCESS:
            raise ValueError(node.configure_error)
        node.trigger_activate()
    finally:
        node.autostarting = False


def destroy_entities(node: Node, entities: Iterable) -> None:
    """Destroy a node's publishers, subscriptions, services and timers (as configure made them)."""
    for entity in entities:
        if isinstance(entity, LifecyclePublisher):
            node.destroy_lifecycle_publisher(entity)
        elif isinstance(entity, Publisher):
            node.destroy_publisher(entity)
        elif isinstance(entity, Service):
            node.destroy_service(entity)
        elif isinstance(entity, Subscription):
            node.destroy_subscription(entity)
        elif isinstance(entity, Timer):
            node.destroy_timer(entity)


def guard_change_state(node: Node, state_label: Callable[[], str]) -> None:
    """
    Answer a change_state request for a transition the current state does not have.

    Answer it (activate while unconfigured, ...) with success false and a warning, as rclcpp
    does: rclpy raises in the service callback, which would end the node's spin. The service
    is found among the node's services by its type (none if the node was made with
    enable_communication_interface=False).
    """
    for service in node.services:
        if service.srv_type is not ChangeState:
            continue
        change_state = service.callback

        def guarded(request, response, change_state=change_state):
            try:
                return change_state(request, response)
            except RuntimeError as exc:  # rclpy's RCLError: the transition is not registered
                node.get_logger().warning(
                    f'transition {request.transition.id} {request.transition.label!r} '
                    f'refused in state {state_label()!r}: {str(exc).split(",")[0]}'
                )
                response.success = False
                return response

        service.callback = guarded


# the nodes whose status is published (publish_status), so spin() starts it once
_STATUS = weakref.WeakKeyDictionary()


def publish_status(
    node: Node,
    publisher: Publisher | None = None,
    summary: Callable[[], tuple[bytes, str, dict]] | None = None,
) -> None:
    """
    Publish the node's status on /diagnostics every STATUS_PERIOD seconds.

    As diagnostic_updater does: one DiagnosticStatus named `<node>: status` with hardware_id
    the node's fully qualified name; `summary()` gives its (level, message, values), by default
    OK 'running'. `publisher` defaults to a new /diagnostics publisher. A second call for the
    same node does nothing.
    """
    if node in _STATUS:
        return
    if publisher is None:
        publisher = node.create_publisher(DiagnosticArray, DIAGNOSTICS, 10)

    def tick() -> None:
        level, message, values = summary() if summary else (DiagnosticStatus.OK, 'running', {})
        status = DiagnosticStatus(
            level=level,
            name=f'{node.get_fully_qualified_name()}: status',
            message=message,
            hardware_id=node.get_fully_qualified_name(),
            values=[KeyValue(key=k, value=str(v)) for k, v in values.items()],
        )
        publisher.publish(
            DiagnosticArray(header=Header(stamp=node.get_clock().now().to_msg()), status=[status])
        )

    # steady time: the status comes every second also under use_sim_time with no /clock yet
    _STATUS[node] = node.create_timer(STATUS_PERIOD, tick, clock=Clock(clock_type=STEADY_TIME))


def spin(make_node: Callable[..., Node], name: str, args: list[str] | None = None) -> NoReturn:
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
    node = executor = None
    try:
        node = make_node(**SEE_OVERRIDES)
        publish_status(node)  # unless the node publishes its own
        # the model (with autostart), torch and rclpy made their long-lived objects at start-up:
        # freezing them keeps the collector's full passes, which scan every tracked object, off
        # the callbacks' latency
        gc.collect()
        gc.freeze()
        executor = make_executor(node)
        executor.add_node(node)
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except (ValueError, FileNotFoundError) as exc:  # bad parameter, checkpoint, table, data
        print(f'{name}: error: {exc}', file=sys.stderr)
        return 1
    finally:
        if executor is not None:
            executor.shutdown(timeout_sec=0)
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0
