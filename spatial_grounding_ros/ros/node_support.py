"""What both executables share: a diagnostic that is also logged, and a main() that spins one
node and shuts down cleanly (start-up errors are one line and exit status 1)."""
from __future__ import annotations

import subprocess
import sys
from typing import Callable

import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.publisher import Publisher
from std_msgs.msg import Header


def report(node: Node, publisher: Publisher, part: str, level: bytes, message: str,
           **values) -> None:
    """Log `message` at `level` and publish it as one DiagnosticStatus named `<node>: part`."""
    # one call site per severity: rclpy refuses to change a call site's severity
    if level == DiagnosticStatus.OK:
        node.get_logger().info(message)
    elif level == DiagnosticStatus.WARN:
        node.get_logger().warning(message)
    else:
        node.get_logger().error(message)
    status = DiagnosticStatus(level=level, name=f"{node.get_fully_qualified_name()}: {part}",
                              message=message, hardware_id="")
    status.values = [KeyValue(key=k, value=str(v)) for k, v in values.items()]
    publisher.publish(DiagnosticArray(header=Header(stamp=node.get_clock().now().to_msg()),
                                      status=[status]))


def spin(make_node: Callable[[], Node], name: str, args: list[str] | None = None) -> int:
    try:
        rclpy.init(args=args)
    except RuntimeError as exc:  # rclpy's RCLError: a missing or malformed --params-file, ...
        print(f"{name}: error: {str(exc).splitlines()[0]}", file=sys.stderr)
        return 1
    node = None
    try:
        node = make_node()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except (ValueError, FileNotFoundError) as exc:  # bad checkpoint, table, data or config
        print(f"{name}: error: {exc}", file=sys.stderr)
        return 1
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


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
