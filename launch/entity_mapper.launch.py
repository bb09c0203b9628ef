# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
Start the entity mapper: a SLAM map (`map`) and landmarks (`landmarks`) -> `entity_map`.

    ros2 launch spatial_grounding_ros entity_mapper.launch.py
    ros2 launch spatial_grounding_ros entity_mapper.launch.py namespace:=robot1 \
        params_file:=/path/to/my_mapper.yaml use_sim_time:=true

Give the grounder the same entity table (its `entity_table` parameter; the shipped mapper
file uses entities_office.yaml). The shipped params file is keyed /**/entity_mapper, so it
applies in any namespace as it is. `map` is relative: remap it to a global map server's with
`map_topic:=/map`.
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
                default_value=os.path.join(share, 'config', 'entity_mapper.yaml'),
                description='ROS parameters file of the entity mapper node',
            ),
            DeclareLaunchArgument(
                'map_topic',
                default_value='map',
                description='the SLAM map topic the node reads (e.g. /map)',
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
            Node(
                package=PACKAGE,
                executable='entity_mapper',
                name='entity_mapper',
                namespace=LaunchConfiguration('namespace'),
                parameters=[
                    LaunchConfiguration('params_file'),
                    {'use_sim_time': LaunchConfiguration('use_sim_time')},
                ],
                remappings=[('map', LaunchConfiguration('map_topic'))],
                arguments=['--ros-args', '--log-level', LaunchConfiguration('log_level')],
                output='screen',
                emulate_tty=True,
            ),
        ]
    )
