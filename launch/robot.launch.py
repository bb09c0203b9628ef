# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
A robot's SLAM map and named landmarks to a goal Nav2 takes: the entity mapper and the grounder.

    ros2 launch spatial_grounding_ros robot.launch.py
    ros2 launch spatial_grounding_ros robot.launch.py namespace:=robot1 map_topic:=/map \
        entity_table:=/path/to/my_landmarks.yaml use_sim_time:=true rviz:=true

The mapper reads `map` (remap with map_topic) and `landmarks` (visualization_msgs/MarkerArray)
and publishes `entity_map`; the grounder reads it and `instruction` and publishes `goal_pose`
(Nav2's bt_navigator listens there), `goal_path` and the value maps. Both take the one
`entity_table` (default the office table, as both nodes' own defaults), so the map's cell values
and the grounder's names always agree. Both are lifecycle nodes; with autostart:=false they wait
for a lifecycle manager. The params files are keyed /**/<node>, so they apply in any namespace.
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
    common = {
        'use_sim_time': LaunchConfiguration('use_sim_time'),
        'autostart': LaunchConfiguration('autostart'),
        'entity_table': LaunchConfiguration('entity_table'),
    }
    log_level = ['--ros-args', '--log-level', LaunchConfiguration('log_level')]
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                'namespace',
                default_value='',
                description='namespace of the nodes, RViz and their relative topics',
            ),
            DeclareLaunchArgument(
                'entity_table',
                default_value='entities_office.yaml',
                description='entity table of both nodes: a file in config/ or a path',
            ),
            DeclareLaunchArgument(
                'map_topic',
                default_value='map',
                description='the SLAM map topic the entity mapper reads (e.g. /map)',
            ),
            DeclareLaunchArgument(
                'grounder_params_file',
                default_value=os.path.join(share, 'config', 'grounder.yaml'),
                description='ROS parameters file of the grounder node',
            ),
            DeclareLaunchArgument(
                'mapper_params_file',
                default_value=os.path.join(share, 'config', 'entity_mapper.yaml'),
                description='ROS parameters file of the entity mapper node',
            ),
            DeclareLaunchArgument(
                'use_sim_time',
                default_value='false',
                description='use the /clock topic (simulation time)',
            ),
            DeclareLaunchArgument(
                'autostart',
                default_value='true',
                description='configure and activate both nodes at start-up',
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
                executable='entity_mapper',
                name='entity_mapper',
                namespace=namespace,
                parameters=[LaunchConfiguration('mapper_params_file'), common],
                remappings=[('map', LaunchConfiguration('map_topic'))],
                arguments=log_level,
                output='screen',
                emulate_tty=True,
            ),
            Node(
                package=PACKAGE,
                executable='grounder',
                name='spatial_grounder',
                namespace=namespace,
                parameters=[LaunchConfiguration('grounder_params_file'), common],
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
                parameters=[{'use_sim_time': LaunchConfiguration('use_sim_time')}],
                output='screen',
                condition=IfCondition(LaunchConfiguration('rviz')),
            ),
        ]
    )
