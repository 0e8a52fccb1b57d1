"""Can the arms reach a task's layout? A reach check with the arms' own IK.

Every place a task sends a hand is a target: each free object where it starts (the palm just
above its top, as for a grasp from above), each articulated link (door, lid, key, lever: the
centre of its parts), each named point and each zone's centre a little above the table. A target
is reached when the Pinocchio IK of either arm (`sim.embodiment.kinematics`, from the home pose)
puts the wrist site (palm centre) there within its 2 mm / 2 degree tolerance in one of the hand
orientations a person would use: palm down, turned about the vertical in 45 degree steps, or palm
forward (facing away from the robot, fingers up), as for pushing a door or turning a screen.
Joint limits count; collisions with the table and the objects do not (a reachable target can still
need a careful approach).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from sim.scene.builder import Scene
from sim.scene.parts import parts_aabb
from sim.scene.sample import zone_centre

# Wrist-site axes (x lateral, y palm normal, z fingers) in the world. Palm down with the fingers
# away from the robot (+y) is how the scripted operator grasps; palm forward faces +y, fingers up.
# Both are mirror symmetric, so they hold for either side.
PALM_DOWN = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
PALM_FORWARD = np.eye(3)
HAND_YAWS_DEG = {"palm_down": (0.0, 45.0, -45.0, 90.0, -90.0, 135.0, -135.0, 180.0),
                 "palm_forward": (0.0, 45.0, -45.0)}
PALM_CLEARANCE_M = 0.03        # palm centre above the top of what it grasps or touches
ZONE_HEIGHT_M = 0.08           # a zone's target: this high above the tabletop at its centre
IK_ITERATIONS = 300


@dataclass(frozen=True)
class ReachTarget:
    name: str                 # "object lemon_1", "point faucet_outlet", "zone left", "link fridge/door"
    pos: np.ndarray           # world position for the wrist site


@dataclass(frozen=True)
class Reach:
    target: ReachTarget
    sides: tuple[str, ...]    # the arms that reach it (empty: unreachable)
    pos_err_m: float          # the best position error over arms and hand orientations

    @property
    def reachable(self) -> bool:
        return bool(self.sides)


def _top_above(centre, quat, parts) -> float:
    """World height of the top of parts whose frame sits at centre/quat."""
    _, hi = parts_aabb(parts, centre, quat)
    return float(hi[2])


def reach_targets(scene: Scene, data: mujoco.MjData | None = None) -> list[ReachTarget]:
    """The layout's targets in the scene as built (home state unless ``data`` is given)."""
    data = data if data is not None else scene.home_data()
    model, task = scene.model, scene.task
    up = np.array([0.0, 0.0, 1.0])
    targets = []
    for name, obj in task.objects.items():
        bid = model.body(name).id
        pos, quat = data.xpos[bid].copy(), data.xquat[bid].copy()
        if obj.base == "free":
            targets.append(ReachTarget(f"object {name}", np.array([*pos[:2], _top_above(pos, quat, obj.parts)])
                                       + PALM_CLEARANCE_M * up))
        for link in obj.links:
            lid = model.body(f"{name}/{link.name}").id
            lo, hi = parts_aabb(link.parts, data.xpos[lid], data.xquat[lid])
            targets.append(ReachTarget(f"link {name}/{link.name}", (lo + hi) / 2))
    for name, point in task.points.items():
        targets.append(ReachTarget(f"point {name}", np.asarray(point, float) + scene.table_height * up))
    for name, zone in task.zones.items():
        targets.append(ReachTarget(f"zone {name}", np.array([*zone_centre(zone), scene.table_height + ZONE_HEIGHT_M])))
    return targets


def hand_orientations() -> list[np.ndarray]:
    """World quaternions of the wrist site to try, palm down first."""
    out = []
    for family, base in (("palm_down", PALM_DOWN), ("palm_forward", PALM_FORWARD)):
        for yaw in np.deg2rad(HAND_YAWS_DEG[family]):
            turn = np.array([[np.cos(yaw), -np.sin(yaw), 0.0], [np.sin(yaw), np.cos(yaw), 0.0], [0.0, 0.0, 1.0]])
            quat = np.zeros(4)
            mujoco.mju_mat2Quat(quat, (turn @ base).ravel())
            out.append(quat)
    return out


def check_reach(scene: Scene, targets: list[ReachTarget] | None = None) -> list[Reach]:
    """Which arms reach each target in one of the hand orientations; deterministic."""
    layout = scene.layout
    homes = {}
    for side, lay in layout.sides.items():
        index = [layout.joint_names.index(j) for j in lay.arm_joints]
        homes[side] = np.asarray(layout.home_qpos, float)[index]
    orientations = hand_orientations()
    out = []
    for target in targets if targets is not None else reach_targets(scene):
        sides, best = [], np.inf
        for side in layout.sides:
            kin = layout.arm_kinematics(side)
            for quat in orientations:
                result = kin.ik(target.pos, quat, homes[side], max_iters=IK_ITERATIONS)
                best = min(best, result.pos_err_m)
                if result.success:
                    sides.append(side)
                    break
        out.append(Reach(target, tuple(sides), float(best)))
    return out

