# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Start the grounder node with its parameters file.

    ros2 launch spatial_grounding_ros grounder.launch.py
    ros2 launch spatial_grounding_ros grounder.launch.py namespace:=robot1 use_sim_time:=true
    ros2 launch spatial_grounding_ros grounder.launch.py params_file:=/path/to/my.yaml \
        autostart:=false log_level:=debug

The shipped params file is keyed /**/spatial_grounder, so it applies in any namespace as it
is (no rewriting). With autostart:=false the node waits, unconfigured, for a lifecycle
manager (Nav2's lifecycle_manager, or `ros2 lifecycle set`).
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

PACKAGE = 'spatial_grounding_ros'


def generate_launch_description():
    share = get_package_share_directory(PACKAGE)
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                'namespace',
                default_value='',
                description='namespace of the node and its relative topics',
            ),
            DeclareLaunchArgument(
                'params_file',
                default_value=os.path.join(share, 'config', 'grounder.yaml'),
                description='ROS parameters file of the grounder node',
            ),
            DeclareLaunchArgument(
                'use_sim_time',
                default_value='false',
                description='use the /clock topic (simulation time)',
            ),
            DeclareLaunchArgument(
                'autostart',
                default_value='true',
                description='configure and activate the node at start-up',
            ),
            DeclareLaunchArgument(
                'log_level',
                default_value='info',
                description='log level: debug, info, warn, error or fatal',
            ),
            Node(
                package=PACKAGE,
                executable='grounder',
                name='spatial_grounder',
                namespace=LaunchConfiguration('namespace'),
                parameters=[
                    LaunchConfiguration('params_file'),
                    {
                        'use_sim_time': LaunchConfiguration('use_sim_time'),
                        'autostart': LaunchConfiguration('autostart'),
                    },
                ],
                arguments=['--ros-args', '--log-level', LaunchConfiguration('log_level')],
                output='screen',
                emulate_tty=True,
            ),
        ]
    )
