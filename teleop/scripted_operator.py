"""A scripted operator that plays the person for pick-and-place plans.

From the task's `demo_plan` (which hand moves which object where) it builds, per hand, a timeline
of wrist keyframes (approach, descend, close, lift, carry, lower, open, retreat) with palm-down
grasps, and solves the arm's Pinocchio IK every step towards the interpolated wrist pose. The
same plan drives any embodiment: nothing here depends on a particular arm or hand.

Where the object sits in the hand and how the hand closes come from the hand file: its
`tabletop_grasp` (object centre in the wrist-site frame, closing targets, which actuators close
late), else its `grasp_probe` power grasp. Where the object goes comes from the plan step's
`place_offset` (see `place_offset`). Like a person, the
operator looks once more where the object sits in the hand when it is above the target, and
corrects the lowering for a slipped grasp.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import mujoco
import numpy as np

from sim.embodiment.description import HandDescription, TabletopGrasp, load_embodiment
from sim.embodiment.mirror import mirror_vec
from sim.errors import SpecError
from sim.scene.builder import Scene
from sim.tasks import TaskSpec

# Palm down, fingers pointing away from the robot (+y world): hand axes (x, y=palm normal, z=fingers).
PALM_DOWN = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
# Segment durations in control steps (60 Hz). Closing takes as long as the real hand needs: at its
# datasheet speeds the RH5DG2's fingers close 1.32 rad in 0.66 s, its thumb yaws 1.18 rad in 0.79 s.
DURATIONS = {"approach": 60, "descend": 40, "close": 40, "close_late": 50, "hold": 10, "lift": 40,
             "carry": 60, "lower": 40, "open": 20, "retreat": 30}
# Hand closure per actuator group (early, late), each 0 = open .. 1 = grasp target. Closing: the
# early actuators (fingers) form a wall, then the late ones (thumb) press the object against it.
# Releasing opens both together: a thumb kept in opposition hooks the fruit as the hand lifts and
# flicks it off the plate.
OPEN, WALL, CLOSED = (0.0, 0.0), (1.0, 0.0), (1.0, 1.0)
APPROACH_HEIGHT_M = 0.12
LIFT_HEIGHT_M = 0.14
RELEASE_GAP_M = 0.005         # lowered to just above the plate: fruit let go higher bounces and rolls
PALM_CLEARANCE_M = 0.004
CLOSED_FRACTION = 0.9         # actuators the grasp does not name: how far towards their far end
MAX_SLIP_M = 0.06             # a larger offset means the object is not in the hand at all
STAGGER_STEPS = 120           # the left hand starts later so the hands never meet over a target
SETTLE_STEPS = 120            # after the last release; reach-and-stop ends earlier on success


def hand_grasp(hand: HandDescription, side: str) -> TabletopGrasp:
    """The hand's declared palm-down grasp (`tabletop_grasp`, else the `grasp_probe` power grasp
    with no staged closing), its object centre mirrored for the left side."""
    if hand.tabletop_grasp is not None:
        grasp = hand.tabletop_grasp
    elif hand.grasp_probe is not None:
        site = hand.wrist_site
        centre = site.rot.T @ (np.asarray(hand.grasp_probe.pos, float) - site.pos)
        grasp = TabletopGrasp(centre=centre, close=dict(hand.grasp_probe.close), late=())
    else:
        grasp = TabletopGrasp(centre=np.zeros(3), close={}, late=())
    return dataclasses.replace(grasp, centre=mirror_vec(grasp.centre)) if side == "left" else grasp


def place_offset(task: TaskSpec, index: int) -> np.ndarray:
    """A plan step's `place_offset`: [dx, dy] from the target's centre, optionally dz from its top
    (negative: lowered into a container and let go just above its floor rather than its rim)."""
    raw = task.demo_plan[index].get("place_offset", [0.0, 0.0])
    if (not isinstance(raw, (list, tuple)) or len(raw) not in (2, 3)
            or not all(isinstance(v, (int, float)) and np.isfinite(v) for v in raw)):
        raise SpecError(task.source, f"demo_plan[{index}].place_offset", "[dx, dy] or [dx, dy, dz] in metres", raw)
    return np.array([*raw, 0.0][:3], float)


def _quat(R: np.ndarray) -> np.ndarray:
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, R.flatten())
    return q


PALM_DOWN_QUAT = _quat(PALM_DOWN)


def _slerp(q0: np.ndarray, q1: np.ndarray, s: float) -> np.ndarray:
    if np.dot(q0, q1) < 0:
        q1 = -q1
    dot = min(1.0, float(np.dot(q0, q1)))
    theta = np.arccos(dot)
    if theta < 1e-6:
        return q1.copy()
    return (np.sin((1 - s) * theta) * q0 + np.sin(s * theta) * q1) / np.sin(theta)


@dataclass
class Keyframe:
    end_step: int
    pos: np.ndarray
    quat: np.ndarray
    closure: np.ndarray     # (early, late)


class SideTimeline:
    """Piecewise-linear wrist path and hand closure of one side."""

    def __init__(self, start_pos, start_quat, start_step: int = 0):
        self.frames = [Keyframe(start_step, np.asarray(start_pos, float), np.asarray(start_quat, float),
                                np.asarray(OPEN, float))]

    @property
    def end(self) -> int:
        return self.frames[-1].end_step

    def add(self, duration: int, pos=None, quat=None, closure=None) -> None:
        last = self.frames[-1]
        self.frames.append(Keyframe(last.end_step + duration, last.pos if pos is None else np.asarray(pos, float),
                                    last.quat if quat is None else np.asarray(quat, float),
                                    last.closure if closure is None else np.asarray(closure, float)))

    def at(self, step: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        prev = self.frames[0]
        for frame in self.frames[1:]:
            if step < frame.end_step:
                s = (step - prev.end_step) / max(1, frame.end_step - prev.end_step)
                s = min(max(s, 0.0), 1.0)
                s = s * s * (3 - 2 * s)     # smoothstep: zero velocity at keyframes
                return (prev.pos + s * (frame.pos - prev.pos), _slerp(prev.quat, frame.quat, s),
                        prev.closure + s * (frame.closure - prev.closure))
            prev = frame
        return prev.pos, prev.quat, prev.closure


class ScriptedOperator:
    name = "scripted"

    def reset(self, scene: Scene, data: mujoco.MjData) -> None:
        self.scene = scene
        model = scene.model
        self.ctrl_home = scene.layout.home_ctrl.copy()
        self.sides = {}
        hand = load_embodiment(scene.layout.embodiment).hand
        for side, lay in scene.layout.sides.items():
            kin = scene.layout.arm_kinematics(side)
            arm_ids = np.array([model.actuator(a).id for a in lay.arm_actuators])
            hand_ids = np.array([model.actuator(a).id for a in lay.hand_actuators])
            open_ = self.ctrl_home[hand_ids]
            lo, hi = model.actuator_ctrlrange[hand_ids].T
            far = np.where(np.abs(hi - open_) >= np.abs(lo - open_), hi, lo)
            closed = open_ + CLOSED_FRACTION * (far - open_)
            grasp = hand_grasp(hand, side)
            group = np.zeros(len(hand_ids), int)       # index into the closure pair
            for i, name in enumerate(lay.hand_actuators):
                short = name.removeprefix(f"{side}_")
                if short in grasp.close:
                    closed[i] = np.clip(grasp.close[short], lo[i], hi[i])
                group[i] = 1 if short in grasp.late else 0
            q_home = self.ctrl_home[arm_ids]
            pos0, quat0 = kin.fk(q_home)
            start = STAGGER_STEPS if side == "left" else 0
            self.sides[side] = {"kin": kin, "arm_ids": arm_ids, "hand_ids": hand_ids, "open": open_,
                                "closed": closed, "group": group, "grasp_centre": grasp.centre,
                                "wrist_site_id": model.site(lay.wrist_site).id, "corrections": [],
                                "q": q_home.copy(), "timeline": SideTimeline(pos0, quat0, start),
                                "home": (pos0, quat0)}
        for i, item in enumerate(scene.task.demo_plan):
            self._plan_pick_place(data, item, place_offset(scene.task, i))
        for side in self.sides.values():
            side["timeline"].add(DURATIONS["approach"], pos=side["home"][0], quat=side["home"][1], closure=OPEN)
        self.length = max(s["timeline"].end for s in self.sides.values()) + SETTLE_STEPS

    def _object_pos(self, data, name) -> np.ndarray:
        return data.xpos[self.scene.object_body_ids[name]].copy()

    def _plan_pick_place(self, data, item: dict, offset_xyz: np.ndarray) -> None:
        side = self.sides[item["hand"]]
        tl: SideTimeline = side["timeline"]
        task = self.scene.task
        obj = task.objects[item["pick"]]
        half_z = obj.half_extents[2]
        # object centre in the wrist-site frame: the hand's grasp centre, lifted clear of the palm
        cx, cy, cz = side["grasp_centre"]
        offset = PALM_DOWN @ np.array([cx, max(cy, half_z + PALM_CLEARANCE_M), cz])
        grasp = self._object_pos(data, item["pick"]) - offset
        target = task.objects[item["place"]]
        place_xy = self._object_pos(data, item["place"])[:2] + offset_xyz[:2]
        place_z = (self._object_pos(data, item["place"])[2] + target.half_extents[2] + offset_xyz[2]
                   + half_z + RELEASE_GAP_M)
        place = np.array([*place_xy, place_z]) - offset
        up = np.array([0, 0, 1.0])
        tl.add(DURATIONS["approach"], pos=grasp + APPROACH_HEIGHT_M * up, quat=PALM_DOWN_QUAT, closure=OPEN)
        tl.add(DURATIONS["descend"], pos=grasp)
        tl.add(DURATIONS["close"], closure=WALL)
        tl.add(DURATIONS["close_late"], closure=CLOSED)
        tl.add(DURATIONS["hold"])
        tl.add(DURATIONS["lift"], pos=grasp + LIFT_HEIGHT_M * up)
        tl.add(DURATIONS["carry"], pos=place + LIFT_HEIGHT_M * up)
        # above the target the operator looks where the object really sits in the hand (it may
        # have slipped while carried) and corrects every later keyframe of this pick for it
        first = len(tl.frames)
        tl.add(DURATIONS["lower"], pos=place)
        tl.add(DURATIONS["open"], closure=OPEN)
        tl.add(DURATIONS["retreat"], pos=place + APPROACH_HEIGHT_M * up)
        carried_at = tl.frames[first - 1].end_step
        side["corrections"].append((carried_at, item["pick"], offset, slice(first, len(tl.frames))))

    def _correct_place(self, side: dict, data: mujoco.MjData, step: int) -> None:
        while side["corrections"] and side["corrections"][0][0] <= step:
            _, name, planned_offset, frames = side["corrections"].pop(0)
            wrist = data.site_xpos[side["wrist_site_id"]]
            error = (self._object_pos(data, name) - wrist) - planned_offset
            error[2] = 0.0      # height is set by the release gap
            if np.linalg.norm(error) > MAX_SLIP_M:     # not in the hand: nothing to correct for
                continue
            for frame in side["timeline"].frames[frames]:    # lower .. the end of this pick
                frame.pos = frame.pos - error

    def act(self, step: int, data: mujoco.MjData) -> np.ndarray:
        ctrl = self.ctrl_home.copy()
        for side in self.sides.values():
            self._correct_place(side, data, step)
            pos, quat, closure = side["timeline"].at(step)
            result = side["kin"].ik(pos, quat, side["q"], max_iters=30)
            side["q"] = result.q
            ctrl[side["arm_ids"]] = result.q
            c = closure[side["group"]]
            ctrl[side["hand_ids"]] = side["open"] + c * (side["closed"] - side["open"])
        return ctrl

    def done(self, step: int) -> bool:
        return step >= self.length
