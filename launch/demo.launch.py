# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The gridworld and the grounder in a closed loop (and RViz on request).

    ros2 launch spatial_grounding_ros demo.launch.py
    ros2 launch spatial_grounding_ros demo.launch.py rviz:=true namespace:=robot1

The gridworld publishes generated PuddleWorld episodes (entity_map, instruction), the
grounder answers each with a goal_pose, the gridworld walks its agent there; both nodes and
RViz (rviz/spatial_grounding.rviz, relative topics) share the namespace. The gridworld waits
for the grounder's subscription before its first episode, so the grounder hears it.
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

PACKAGE = 'spatial_grounding_ros'


def generate_launch_description():
    share = get_package_share_directory(PACKAGE)
    namespace = LaunchConfiguration('namespace')
    common = {'use_sim_time': LaunchConfiguration('use_sim_time')}
    log_level = ['--ros-args', '--log-level', LaunchConfiguration('log_level')]
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                'namespace',
                default_value='',
                description='namespace of the nodes, RViz and their topics',
            ),
            DeclareLaunchArgument(
                'grounder_params_file',
                default_value=os.path.join(share, 'config', 'grounder.yaml'),
                description='ROS parameters file of the grounder node',
            ),
            DeclareLaunchArgument(
                'gridworld_params_file',
                default_value=os.path.join(share, 'config', 'gridworld.yaml'),
                description='ROS parameters file of the gridworld node',
            ),
            DeclareLaunchArgument(
                'use_sim_time',
                default_value='false',
                description='use the /clock topic (simulation time)',
            ),
            DeclareLaunchArgument(
                'log_level',
                default_value='info',
                description='log level: debug, info, warn, error or fatal',
            ),
            DeclareLaunchArgument(
                'rviz',
                default_value='false',
                description='start RViz with rviz/spatial_grounding.rviz',
            ),
            Node(
                package=PACKAGE,
                executable='grounder',
                name='spatial_grounder',
                namespace=namespace,
                # the gridworld's maps are PuddleWorld's (the shipped file's table: office)
                parameters=[
                    LaunchConfiguration('grounder_params_file'),
                    {**common, 'entity_table': 'entities_puddleworld.yaml'},
                ],
                arguments=log_level,
                output='screen',
                emulate_tty=True,
            ),
            Node(
                package=PACKAGE,
                executable='gridworld',
                name='gridworld',
                namespace=namespace,
                parameters=[
                    LaunchConfiguration('gridworld_params_file'),
                    {**common, 'start_after_subscribers': 1},
                ],
                arguments=log_level,
                output='screen',
                emulate_tty=True,
            ),
            Node(
                package='rviz2',
                executable='rviz2',
                name='rviz2',
                namespace=namespace,
                arguments=['-d', os.path.join(share, 'rviz', 'spatial_grounding.rviz')],
                parameters=[common],
                output='screen',
                condition=IfCondition(LaunchConfiguration('rviz')),
            ),
        ]
    )
