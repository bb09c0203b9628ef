#!/usr/bin/env bash
# Build the interface package interfaces/spatial_grounding_interfaces (GroundInstruction.srv)
# into a virtual environment made from requirements.txt, without a ROS install:
#
#   tools/build_interfaces.sh [VENV]          # default .venv; `make setup` runs it
#
# The ament_cmake and rosidl wheels of requirements.txt install ROS's CMake modules,
# generators and typesupports into the venv's prefix (share/, lib/, include/), as a ROS
# install has them in /opt/ros/jazzy. The package is built with the machine's cmake and
# compiler against that prefix and installed into it: its libraries into VENV/lib (which
# the ROS wheels' start-up hook puts on LD_LIBRARY_PATH, so rclpy loads the C typesupport),
# its Python module into site-packages, its share/ and ament index entry beside the
# message packages'. Run again, it rebuilds only what changed (the build folder is kept in
# VENV/build). On a ROS system build it with colcon instead (docs/ros.md).
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=$(realpath "${1:-.venv}")
PY="$VENV/bin/python"
BUILD="$VENV/build/spatial_grounding_interfaces"
mkdir -p "$VENV/build"
# the wheels' CMake exports name their build machine's Python include folders
"$PY" tools/fix_ros_wheels.py
export AMENT_PREFIX_PATH="$VENV" CMAKE_PREFIX_PATH="$VENV" PATH="$VENV/bin:$PATH"
cmake -S interfaces/spatial_grounding_interfaces -B "$BUILD" \
    -DCMAKE_INSTALL_PREFIX="$VENV" -DPython3_EXECUTABLE="$PY" \
    -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=OFF > "$BUILD.log" 2>&1 ||
    { cat "$BUILD.log"; exit 1; }
cmake --build "$BUILD" -j "$(nproc)" >> "$BUILD.log" 2>&1 || { cat "$BUILD.log"; exit 1; }
cmake --install "$BUILD" >> "$BUILD.log" 2>&1 || { cat "$BUILD.log"; exit 1; }
# from a folder of no package: the module must come from the venv
(cd / && "$PY" -c 'from spatial_grounding_interfaces.srv import GroundInstruction') ||
    { echo "build_interfaces: the built module does not import"; exit 1; }
echo "build_interfaces: spatial_grounding_interfaces installed into $VENV"
