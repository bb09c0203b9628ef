"""
ROS 2 adapters: message conversion, the grounder and gridworld nodes, bag I/O.

The only part of the package that imports rclpy and message types.
"""
