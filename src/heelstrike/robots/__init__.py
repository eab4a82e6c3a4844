"""Real robots (URDF/MJCF through Pinocchio): contacts in 3-D and per-contact impact laws.

Needs the optional extra ``heelstrike[robots]`` (packages ``pin`` and ``example-robot-data``);
importing this package works without it, loading a robot raises :class:`RobotError`.
"""

from heelstrike.robots.contacts import (
    ContactSpec,
    RobotImpact,
    centre_of_pressure,
    contact_heights,
    contact_jacobian,
    ground_admissible,
    inert_energy_split,
    inert_energy_split_batch,
    inert_impact_batch,
    mass_matrices_and_jacobians,
    parse_contact,
    robot_impact,
    robot_matrices,
)
from heelstrike.robots.loading import (
    SHIPPED_ROBOTS,
    Robot,
    RobotError,
    RobotSpec,
    list_robots,
    load_mjcf,
    load_robot,
    load_urdf,
    robot_data_dir,
)
from heelstrike.robots.states import (
    JointLimitViolation,
    gait_configuration,
    gait_state,
    gait_velocity,
    joint_limit_violations,
)
from heelstrike.robots.study import RobotStudy, robot_heel_strike_study

__all__ = [
    "SHIPPED_ROBOTS",
    "ContactSpec",
    "JointLimitViolation",
    "Robot",
    "RobotError",
    "RobotImpact",
    "RobotSpec",
    "RobotStudy",
    "centre_of_pressure",
    "contact_heights",
    "contact_jacobian",
    "gait_configuration",
    "gait_state",
    "gait_velocity",
    "ground_admissible",
    "inert_energy_split",
    "inert_energy_split_batch",
    "inert_impact_batch",
    "joint_limit_violations",
    "list_robots",
    "load_mjcf",
    "load_robot",
    "load_urdf",
    "mass_matrices_and_jacobians",
    "parse_contact",
    "robot_data_dir",
    "robot_heel_strike_study",
    "robot_impact",
    "robot_matrices",
]
