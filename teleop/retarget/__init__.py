"""DexPilot retargeting of operator hand keypoints for every catalog hand (``dexpilot.py``), and the
commander that merges hand targets with the arm IK into one joint-position command (``command.py``)."""

from .command import Command, TeleopCommander
from .dexpilot import DexPilotConfig, DexPilotRetargeter
from .hand_model import HandKinematics

__all__ = ["Command", "DexPilotConfig", "DexPilotRetargeter", "HandKinematics", "TeleopCommander"]
