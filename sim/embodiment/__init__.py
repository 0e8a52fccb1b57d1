"""Bimanual arm + dexterous-hand embodiments, built with MjSpec from declarative catalog files.

    load_arm(name), load_hand(name), load_embodiment(name), embodiment_names()
    add_bimanual_robot(spec, embodiment) -> RobotLayout
    ArmKinematics (Pinocchio fk / ik of the wrist site)
"""

from .builder import RobotLayout, SideLayout, add_bimanual_robot, servo_gains
from .description import (ArmDescription, DescriptionError, EmbodimentDescription, HandDescription,
                          arm_names, embodiment_names, hand_names, load_arm, load_embodiment, load_hand)
from .kinematics import ArmKinematics, IKResult

__all__ = [
    "ArmDescription", "ArmKinematics", "DescriptionError", "EmbodimentDescription", "HandDescription",
    "IKResult", "RobotLayout", "SideLayout", "add_bimanual_robot", "arm_names", "embodiment_names",
    "hand_names", "load_arm", "load_embodiment", "load_hand", "servo_gains",
]
