"""What a planner may use of the scripted operator (teleop/scripted_operator.py), as a Protocol: the
planners type their `op` with it instead of importing ScriptedOperator, which imports the planners."""

from __future__ import annotations

from typing import Callable, Protocol

import mujoco
import numpy as np

from sim.scene.builder import Scene


class PlanningOperator(Protocol):
    scene: Scene
    sides: dict[str, dict]              # per hand: kinematics, actuator ids, timeline, open/closed targets
    link_angles: dict[str, float]       # where earlier `turn` steps leave each hinged link (planned)

    def object_pos(self, data: mujoco.MjData, name: str) -> np.ndarray: ...

    def leaves(self, name: str, pos: np.ndarray, on: str | None = None) -> None: ...

    def planned_place(self, data: mujoco.MjData, name: str, step: int) -> tuple[np.ndarray, str | None]: ...

    def planned_by_arrival(self, side: dict, data: mujoco.MjData, name: str, approach: slice) -> np.ndarray: ...

    def set_off(self, side: dict, data: mujoco.MjData, item: dict, duration: int, pos, quat=None, hand=None,
                carried: tuple[str, np.ndarray] | None = None, roll_first: bool = False) -> None: ...

    def set_off_home(self, side: dict, data: mujoco.MjData, hand=None) -> None: ...

    def look_again(self, side: dict, name: str, data: mujoco.MjData, first: int, end: int,
                   planned: np.ndarray | None = None) -> None: ...

    @staticmethod
    def on_frame_end(side: dict, frame: int, adjust: Callable) -> None: ...

    @staticmethod
    def power(side: dict, closure: tuple[float, float]) -> np.ndarray: ...
