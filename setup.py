# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
ament_python package.

`colcon build` installs the node executables into lib/spatial_grounding_ros (where `ros2 run`
looks); `pip install -e .` makes the same entry points console scripts in a virtual environment.
"""

from glob import glob

from setuptools import find_packages, setup

PACKAGE = 'spatial_grounding_ros'

setup(
    name=PACKAGE,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    package_data={PACKAGE: ['checkpoints/*.pt', 'data/natural/*.yaml']},
    data_files=[
        ('share/ament_index/resource_index/packages', [f'resource/{PACKAGE}']),
        (f'share/{PACKAGE}', ['package.xml']),
        (f'share/{PACKAGE}/config', glob('config/*.yaml')),
        (f'share/{PACKAGE}/launch', glob('launch/*.launch.py')),
        (f'share/{PACKAGE}/rviz', glob('rviz/*.rviz')),
        (f'share/{PACKAGE}', ['LICENSE']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='spatial_grounding_ros developers',
    maintainer_email='dev@spatial-grounding.local',
    description='Grounding spatial references to value maps and navigation goals (t-RNetAttn).',
    license='MIT',
    tests_require=['pytest'],
    entry_points={
        'console_scripts': [
            'spatial-grounding = spatial_grounding_ros.cli:main',
            'grounder = spatial_grounding_ros.ros.grounder_node:main',
            'gridworld = spatial_grounding_ros.ros.gridworld_node:main',
            'entity_mapper = spatial_grounding_ros.ros.entity_mapper_node:main',
        ]
    },
)
