# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The names of the nodes' topics and services, and each topic's message type.

Every name is relative, so a namespace (`-r __ns:=/robot`) or a remap (`-r goal_pose:=...`)
moves it, except DIAGNOSTICS, which is absolute as ROS's aggregators expect. The names live
here, below every layer rather than in ros/, because data/bags.py reads the bags recorded from
these topics without ROS; plain strings, no message module is imported.
"""

ENTITY_MAP = 'entity_map'
INSTRUCTION = 'instruction'
GOAL_POSE = 'goal_pose'
# a sequence's goals in order (nav_msgs/Path); an empty path: stop
GOAL_PATH = 'goal_path'
VALUE_MAP = 'value_map'
VALUE_MAP_RAW = 'value_map_raw'
VALUE_MAP_IMAGE = 'value_map_image'
RELATION_MAP = 'relation_map'
TRUE_GOAL = 'true_goal'
TRUE_VALUE_MAP = 'true_value_map'
TRUE_REWARD_MAP = 'true_reward_map'
AGENT_POSE = 'agent_pose'
REWARD = 'reward'
TERMINATED = 'terminated'
ACTION = 'action'
# the robot's pose the grounder reads for goal_heading: keep
ROBOT_POSE = 'robot_pose'
DIAGNOSTICS = '/diagnostics'
# the remap rule that moves a node's DIAGNOSTICS into its namespace (the demo, the gym client)
DIAGNOSTICS_INTO_NAMESPACE = f'{DIAGNOSTICS}:={DIAGNOSTICS.lstrip("/")}'

# the gridworld node's services (std_srvs/srv/Trigger)
NEXT_EPISODE = 'next_episode'
RESET_EPISODE = 'reset_episode'
# the grounder node's service (spatial_grounding_interfaces/srv/GroundInstruction)
GROUND_INSTRUCTION = 'ground_instruction'

MSGTYPES = {
    ENTITY_MAP: 'nav_msgs/msg/OccupancyGrid',
    INSTRUCTION: 'std_msgs/msg/String',
    TRUE_GOAL: 'geometry_msgs/msg/PoseStamped',
    TRUE_VALUE_MAP: 'std_msgs/msg/Float32MultiArray',
    TRUE_REWARD_MAP: 'std_msgs/msg/Float32MultiArray',
    VALUE_MAP_RAW: 'std_msgs/msg/Float32MultiArray',
    VALUE_MAP_IMAGE: 'sensor_msgs/msg/Image',
    VALUE_MAP: 'nav_msgs/msg/OccupancyGrid',
    RELATION_MAP: 'nav_msgs/msg/OccupancyGrid',
    GOAL_POSE: 'geometry_msgs/msg/PoseStamped',
    GOAL_PATH: 'nav_msgs/msg/Path',
    AGENT_POSE: 'geometry_msgs/msg/PoseStamped',
    ROBOT_POSE: 'geometry_msgs/msg/PoseStamped',
    REWARD: 'std_msgs/msg/Float32',
    TERMINATED: 'std_msgs/msg/Bool',
    ACTION: 'std_msgs/msg/Int32',
    DIAGNOSTICS: 'diagnostic_msgs/msg/DiagnosticArray',
}
# the nodes publish these transient local (a late subscriber still gets the last message): the
# map, an episode's instruction and truth, and the grounder's maps
LATCHED = frozenset(
    {
        ENTITY_MAP,
        INSTRUCTION,
        TRUE_GOAL,
        TRUE_VALUE_MAP,
        TRUE_REWARD_MAP,
        VALUE_MAP_RAW,
        VALUE_MAP_IMAGE,
        VALUE_MAP,
        RELATION_MAP,
    }
)
