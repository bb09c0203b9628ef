"""Start the grounder node with its parameters file:

    ros2 launch spatial_grounding_ros grounder.launch.py
    ros2 launch spatial_grounding_ros grounder.launch.py params_file:=/path/to/my.yaml namespace:=robot1
"""
import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

PACKAGE = "spatial_grounding_ros"


def generate_launch_description():
    default_params = os.path.join(get_package_share_directory(PACKAGE), "config",
                                  "grounder.yaml")
    return LaunchDescription([
        DeclareLaunchArgument("params_file", default_value=default_params,
                              description="ROS parameters file of the grounder node"),
        DeclareLaunchArgument("namespace", default_value="",
                              description="namespace of the node and its relative topics"),
        Node(package=PACKAGE, executable="grounder", name="spatial_grounder",
             namespace=LaunchConfiguration("namespace"),
             parameters=[LaunchConfiguration("params_file")], output="screen",
             emulate_tty=True),
    ])
