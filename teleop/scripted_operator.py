"""A scripted operator that plays the person for a task's `demo_plan`.

From the plan (which hand moves which object where: pick-and-place steps, and drag steps that pull
a container into a zone) it builds, per hand, a timeline of wrist keyframes and hand actuator
targets (approach, descend, close, lift, carry, lower, open, retreat), palm down or with the
fingers pitched down. `intent` gives the timeline's wrist pose and hand targets at a step; `act`
solves the arm's Pinocchio IK towards it (the direct joint path; teleop/scripted_stream.py sends
the same intent through the person's stream interface). The same plan drives any embodiment:
nothing here depends on a particular arm or hand.

Where the object sits in the hand and how the hand closes come from the hand file: its
`tabletop_grasp` (object centre in the wrist-site frame, closing targets, which actuators close
late), else its `grasp_probe` power grasp; or, for a plan step with `grasp: pinch`, a pinch found
from the hand's kinematics (teleop/pinch_grasp.py). A plan step's `approach_pitch_deg` tilts the
fingers down for the whole pick. Where the object goes comes from the plan step's
`place_offset` (see `place_offset`). Like a person, the
operator looks once more where the object sits in the hand when it is above the target, and
corrects the lowering for a slipped grasp.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass

import mujoco
import numpy as np

from sim.embodiment.description import HandDescription, TabletopGrasp, load_embodiment
from sim.embodiment.mirror import M, mirror_vec
from sim.errors import SpecError
from sim.scene.builder import Scene
from sim.scene.sample import zone_centre
from sim.tasks import TABLE_TARGET, TaskSpec
from teleop.pinch_grasp import fingertips_in_site_frame, pinch_axis_in_site_frame, pinch_grasp, pinch_preshape

# Palm down, fingers pointing away from the robot (+y world): hand axes (x, y=palm normal, z=fingers).
PALM_DOWN = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
UP = np.array([0.0, 0.0, 1.0])
# Segment durations in control steps (60 Hz). Closing takes as long as the real hand needs: at its
# datasheet speeds the RH5DG2's fingers close 1.32 rad in 0.66 s, its thumb yaws 1.18 rad in 0.79 s.
DURATIONS = {"approach": 60, "descend": 40, "close": 40, "close_late": 50, "hold": 10, "lift": 40,
             "carry": 60, "lower": 40, "open": 20, "retreat": 30}
# Power grasp closure per actuator group (early, late), each 0 = open .. 1 = grasp target. Closing:
# the early actuators (fingers) form a wall, then the late ones (thumb) press the object against it.
# Releasing opens both together: a thumb kept in opposition hooks the fruit as the hand lifts and
# flicks it off the plate.
WALL, CLOSED = (1.0, 0.0), (1.0, 1.0)
PINCH_SPREAD_MARGIN_M = 0.025  # pinch pre-shape: pads this much wider apart than the object
APPROACH_HEIGHT_M = 0.12
LIFT_HEIGHT_M = 0.14
RELEASE_GAP_M = 0.005         # lowered to just above the plate: fruit let go higher bounces and rolls
PALM_CLEARANCE_M = 0.004
CLOSED_FRACTION = 0.9         # actuators the grasp does not name: how far towards their far end
MAX_SLIP_M = 0.06             # a larger offset means the object is not in the hand at all
DRAG_PITCH_DEG = 20.0         # drag: fingers tilted down into the container
DRAG_INSET_M = 0.015          # drag: curled fingertips this far inside the leading wall
DRAG_DEPTH_M = 0.02           # drag: ... and this far below its rim
DRAG_SPEED_M_PER_STEP = 0.0025  # drag: 0.15 m/s
STAGGER_STEPS = 120           # the left hand starts later so the hands never meet over a target
SETTLE_STEPS = 120            # after the last release; reach-and-stop ends earlier on success


def hand_grasp(hand: HandDescription, side: str) -> TabletopGrasp:
    """The hand's declared palm-down grasp (`tabletop_grasp`, else the `grasp_probe` power grasp
    with no staged closing), its object centre mirrored for the left side."""
    if hand.tabletop_grasp is not None:
        grasp = hand.tabletop_grasp
    elif hand.grasp_probe is not None:
        centre = hand.wrist_site.to_local(hand.grasp_probe.pos)
        grasp = TabletopGrasp(centre=centre, close=dict(hand.grasp_probe.close), late=())
    else:
        grasp = TabletopGrasp(centre=np.zeros(3), close={}, late=())
    return dataclasses.replace(grasp, centre=mirror_vec(grasp.centre)) if side == "left" else grasp


def place_offset(item: dict) -> np.ndarray:
    """A plan step's `place_offset` (checked when the task loads): [dx, dy] from the target's centre,
    optionally dz from its top (negative: lowered into a container and let go just above its floor
    rather than its rim); for `place: table`, the [x, y] of the table top to set the object down at."""
    return np.array([*item.get("place_offset", [0.0, 0.0]), 0.0][:3], float)


def approach_pitch(item: dict) -> float:
    """A plan step's `approach_pitch_deg`: how far the fingers point down from horizontal (0 = palm
    down, fingers forward). A person tilts the hand for small or low objects so the forearm stays
    clear of the table; a robot arm's wrist links need the same."""
    return float(item.get("approach_pitch_deg", 0.0))


@functools.lru_cache(maxsize=None)
def level_pinch_pitch(hand_name: str) -> float:
    """The finger pitch (degrees, 0..60) that levels the hand's pinch axis, so that the thumb and
    the fingers come down to the same height beside a low object instead of the lower one landing
    on it; 0 where the axis already falls towards the fingers (pitching would only tilt it more)."""
    axis = pinch_axis_in_site_frame(hand_name)
    pitches = np.arange(0.0, 61.0)
    elevation = np.array([(pitched_palm_down(p) @ axis)[2] for p in pitches])
    return float(pitches[np.argmin(np.abs(elevation))]) if elevation[0] > 0 else 0.0


def grasp_kind(item: dict) -> str:
    """A plan step's `grasp`: "power" (the hand's palm grasp, default) or "pinch" (thumb against the
    first fingers' pads, for objects too small for the palm; teleop/pinch_grasp.py)."""
    return item.get("grasp", "power")


def pitched_palm_down(pitch_deg: float) -> np.ndarray:
    """PALM_DOWN with the fingers turned ``pitch_deg`` down about the world x axis."""
    a = np.radians(pitch_deg)
    about_x = np.array([[1.0, 0.0, 0.0], [0.0, np.cos(a), np.sin(a)], [0.0, -np.sin(a), np.cos(a)]])
    return about_x @ PALM_DOWN


def _quat(R: np.ndarray) -> np.ndarray:
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, R.flatten())
    return q


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
    hand: np.ndarray        # hand actuator targets (layout order)


class SideTimeline:
    """Piecewise-linear wrist path and hand actuator targets of one side."""

    def __init__(self, start_pos, start_quat, start_hand, start_step: int = 0):
        self.frames = [Keyframe(start_step, np.asarray(start_pos, float), np.asarray(start_quat, float),
                                np.asarray(start_hand, float))]

    @property
    def end(self) -> int:
        return self.frames[-1].end_step

    def add(self, duration: int, pos=None, quat=None, hand=None) -> None:
        last = self.frames[-1]
        self.frames.append(Keyframe(last.end_step + duration, last.pos if pos is None else np.asarray(pos, float),
                                    last.quat if quat is None else np.asarray(quat, float),
                                    last.hand if hand is None else np.asarray(hand, float)))

    def at(self, step: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        prev = self.frames[0]
        for frame in self.frames[1:]:
            if step < frame.end_step:
                s = (step - prev.end_step) / max(1, frame.end_step - prev.end_step)
                s = min(max(s, 0.0), 1.0)
                s = s * s * (3 - 2 * s)     # smoothstep: zero velocity at keyframes
                return (prev.pos + s * (frame.pos - prev.pos), _slerp(prev.quat, frame.quat, s),
                        prev.hand + s * (frame.hand - prev.hand))
            prev = frame
        return prev.pos, prev.quat, prev.hand


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
            pinch = pinch_grasp(hand.name)      # cached per hand
            self.sides[side] = {"kin": kin, "arm_ids": arm_ids, "hand_ids": hand_ids, "open": open_,
                                "closed": closed, "group": group, "grasp_centre": grasp.centre,
                                "pinch_close": np.clip(pinch.close, lo, hi), "hand": hand.name,
                                "wrist_site_id": model.site(lay.wrist_site).id, "corrections": [], "reaims": [],
                                "q": q_home.copy(), "timeline": SideTimeline(pos0, quat0, open_, start),
                                "home": (pos0, quat0)}
        ends: list[int] = []         # each step's last control step
        for item in scene.task.demo_plan:
            tl = self.sides[item["hand"]]["timeline"]
            wait_until = max((ends[j] for j in item.get("after", [])), default=0)
            if wait_until > tl.end:
                tl.add(wait_until - tl.end)     # the hand holds still until those steps are done
            if "drag" in item:
                self._plan_drag(data, item)
            else:
                self._plan_pick_place(data, item, place_offset(item))
            ends.append(tl.end)
        for side in self.sides.values():
            side["timeline"].add(DURATIONS["approach"], pos=side["home"][0], quat=side["home"][1], hand=side["open"])
        self.length = max(s["timeline"].end for s in self.sides.values()) + SETTLE_STEPS

    def _object_pos(self, data, name) -> np.ndarray:
        return data.xpos[self.scene.object_body_ids[name]].copy()

    def _plan_pick_place(self, data, item: dict, offset_xyz: np.ndarray) -> None:
        side = self.sides[item["hand"]]
        tl: SideTimeline = side["timeline"]
        task = self.scene.task
        obj = task.objects[item["pick"]]
        half_z = obj.half_extents[2]
        pinch = grasp_kind(item) == "pinch"
        if pinch and "approach_pitch_deg" not in item:
            hand_rot = pitched_palm_down(level_pinch_pitch(side["hand"]))
        else:
            hand_rot = pitched_palm_down(approach_pitch(item))
        hand_quat = _quat(hand_rot)
        open_ = side["open"]
        if pinch:
            # come down with the pads spread wider than the object, its centre midway between them
            axis = pinch_axis_in_site_frame(side["hand"])
            axis = hand_rot @ (mirror_vec(axis) if item["hand"] == "left" else axis)
            body_rot = data.xmat[self.scene.object_body_ids[item["pick"]]].reshape(3, 3)
            width = 2.0 * float(np.abs(body_rot.T @ axis) @ obj.half_extents) + PINCH_SPREAD_MARGIN_M
            ready, centre = pinch_preshape(side["hand"], open_, side["pinch_close"], width)
            offset = hand_rot @ (mirror_vec(centre) if item["hand"] == "left" else centre)
            closing = [(DURATIONS["close"] + DURATIONS["close_late"], side["pinch_close"])]
        else:
            # object centre in the wrist-site frame: the hand's grasp centre, lifted clear of the palm
            cx, cy, cz = side["grasp_centre"]
            offset = hand_rot @ np.array([cx, max(cy, half_z + PALM_CLEARANCE_M), cz])
            closing = [(DURATIONS["close"], self._power(side, WALL)), (DURATIONS["close_late"], self._power(side, CLOSED))]
            ready = open_
        grasp = self._object_pos(data, item["pick"]) - offset
        if item["place"] == TABLE_TARGET:       # set down at a spot of the table top
            place_xy = offset_xyz[:2]
            place_z = self.scene.table_height + offset_xyz[2] + obj.rest_height + RELEASE_GAP_M
        else:
            target = task.objects[item["place"]]
            place_xy = self._object_pos(data, item["place"])[:2] + offset_xyz[:2]
            place_z = (self._object_pos(data, item["place"])[2] + target.half_extents[2] + offset_xyz[2]
                       + half_z + RELEASE_GAP_M)
        place = np.array([*place_xy, place_z]) - offset
        reach = len(tl.frames)
        tl.add(DURATIONS["approach"], pos=grasp + APPROACH_HEIGHT_M * UP, quat=hand_quat, hand=ready)
        tl.add(DURATIONS["descend"], pos=grasp)
        for duration, targets in closing:
            tl.add(duration, hand=targets)
        tl.add(DURATIONS["hold"])
        tl.add(DURATIONS["lift"], pos=grasp + LIFT_HEIGHT_M * UP)
        self._look_again(side, item["pick"], data, reach, len(tl.frames))
        carry = len(tl.frames)
        tl.add(DURATIONS["carry"], pos=place + LIFT_HEIGHT_M * UP)
        # above the target the operator looks where the object really sits in the hand (it may
        # have slipped while carried) and corrects every later keyframe of this pick for it
        first = len(tl.frames)
        tl.add(DURATIONS["lower"], pos=place)
        tl.add(DURATIONS["open"], hand=open_)
        tl.add(DURATIONS["retreat"], pos=place + APPROACH_HEIGHT_M * UP)
        carried_at = tl.frames[first - 1].end_step
        side["corrections"].append((carried_at, item["pick"], offset, slice(first, len(tl.frames))))
        if item["place"] != TABLE_TARGET:
            self._look_again(side, item["place"], data, carry, len(tl.frames))

    def _plan_drag(self, data, item: dict) -> None:
        """Drag a container across the table into the zone, the way a person pulls a box or a bowl
        towards themselves: the hand, palm down and fingers pointing into the container over the
        wall on the side it is to go, curls its fingers (the power grasp's early actuators) to hook
        them inside that wall, draws the container until its centre is over the zone's centre,
        opens and rises. Palm down keeps the arm in the configuration it already has."""
        side = self.sides[item["hand"]]
        tl: SideTimeline = side["timeline"]
        obj = self.scene.task.objects[item["drag"]]
        body = self.scene.object_body_ids[item["drag"]]
        centre = data.xpos[body].copy()
        way = zone_centre(self.scene.task.zones[item["to_zone"]]) - centre[:2]
        distance = float(np.linalg.norm(way))
        if distance < 1e-6:
            return
        d = np.array([*(way / distance), 0.0])
        # fingers point at -d: PALM_DOWN's fingers (+y) turned about z
        yaw = np.arctan2(-d[1], -d[0]) - np.pi / 2
        c, s_ = np.cos(yaw), np.sin(yaw)
        hand_rot = np.array([[c, -s_, 0.0], [s_, c, 0.0], [0.0, 0.0, 1.0]]) @ pitched_palm_down(DRAG_PITCH_DEG)
        hooked = self._power(side, WALL)
        tips = fingertips_in_site_frame(side["hand"], hooked)[1:]        # the fingers, not the thumb
        if item["hand"] == "left":
            tips = tips @ M             # M is its own transpose: each row mirrored
        hook_tip = hand_rot @ tips.mean(axis=0)                         # curled fingertips from the site
        target = np.array([*centre[:2], centre[2] + obj.half_extents[2] - DRAG_DEPTH_M])
        target += d * (self._wall_distance(data, body, target, d) - DRAG_INSET_M)
        start = target - hook_tip
        end = start + d * distance
        reach = len(tl.frames)
        tl.add(DURATIONS["approach"], pos=start + APPROACH_HEIGHT_M * UP, quat=_quat(hand_rot), hand=side["open"])
        tl.add(DURATIONS["descend"], pos=start)
        self._look_again(side, item["drag"], data, reach, len(tl.frames))
        tl.add(DURATIONS["close"], hand=hooked)
        tl.add(int(max(DURATIONS["carry"], distance / DRAG_SPEED_M_PER_STEP)), pos=end)
        tl.add(DURATIONS["close"], hand=side["open"])
        tl.add(DURATIONS["retreat"], pos=end + APPROACH_HEIGHT_M * UP)

    def _wall_distance(self, data: mujoco.MjData, body: int, point: np.ndarray, d: np.ndarray) -> float:
        """How far the container's own wall is from ``point`` (inside it) along ``d``: a ray against
        each of its geoms, so a round bowl and a box both come out exact."""
        model, hits = self.scene.model, []
        for g in range(model.body_geomadr[body], model.body_geomadr[body] + model.body_geomnum[body]):
            dist = mujoco.mju_rayGeom(data.geom_xpos[g], data.geom_xmat[g], model.geom_size[g], point, d,
                                      int(model.geom_type[g]))
            if dist >= 0:
                hits.append(dist)
        if not hits:
            raise SpecError(self.scene.task.source, "demo_plan.drag", "a container whose walls surround its centre",
                            f"no wall of {model.body(body).name} along {np.round(d, 3).tolist()}")
        return min(hits)

    def _look_again(self, side: dict, name: str, data, first: int, end: int) -> None:
        """When the hand sets off towards ``name`` (the start of frame ``first``), the operator looks
        where it is now (an earlier step may have pushed or nudged it) and moves frames
        ``first``..``end`` with it (horizontally: heights come from the object's size)."""
        side["reaims"].append((side["timeline"].frames[first - 1].end_step, name, self._object_pos(data, name),
                               slice(first, end)))

    def _reaim(self, side: dict, data: mujoco.MjData, step: int) -> None:
        while side["reaims"] and side["reaims"][0][0] <= step:
            _, name, planned, frames = side["reaims"].pop(0)
            moved = self._object_pos(data, name) - planned
            moved[2] = 0.0
            for frame in side["timeline"].frames[frames]:
                frame.pos = frame.pos + moved

    @staticmethod
    def _power(side: dict, closure: tuple[float, float]) -> np.ndarray:
        c = np.asarray(closure, float)[side["group"]]
        return side["open"] + c * (side["closed"] - side["open"])

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

    def intent(self, step: int, data: mujoco.MjData) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """What the operator wants at ``step``, per side: the wrist-site pose (pos, quat w x y z,
        world) and the hand actuator targets (layout order). Looks at ``data`` when a hand sets off
        towards an object or a target (it may have been moved) and before lowering a carried object
        (it may have slipped in the hand). Both the direct joint path (``act``) and the
        stream path (``teleop/scripted_stream.py``) start from this."""
        out = {}
        for name, side in self.sides.items():
            self._reaim(side, data, step)
            self._correct_place(side, data, step)
            out[name] = side["timeline"].at(step)
        return out

    def act(self, step: int, data: mujoco.MjData) -> np.ndarray:
        ctrl = self.ctrl_home.copy()
        for name, (pos, quat, hand) in self.intent(step, data).items():
            side = self.sides[name]
            result = side["kin"].ik(pos, quat, side["q"], max_iters=30)
            side["q"] = result.q
            ctrl[side["arm_ids"]] = result.q
            ctrl[side["hand_ids"]] = hand
        return ctrl

    def done(self, step: int) -> bool:
        return step >= self.length
