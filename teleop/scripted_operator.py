"""A scripted operator that plays the person for a task's `demo_plan` (sim/demo_plan.py).

From the plan (which hand does what: pick-and-place, drag, ...) it builds, per hand, a timeline of
wrist keyframes and hand actuator targets; each step kind has its planner in teleop/plan_steps/.
`intent` gives the timeline's wrist pose and hand targets at a step; `act` solves the arm's
Pinocchio IK towards it (the direct joint path; teleop/scripted_stream.py sends the same intent
through the person's stream interface). The same plan drives any embodiment: nothing here depends
on a particular arm or hand. Like a person, the operator looks again where an object is when a hand
sets off for it, and where a carried object sits in the hand before lowering it.
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import mujoco
import numpy as np

from sim.demo_plan import BOTH_HANDS
from sim.physics import CONTROL_HZ
from sim.embodiment.description import HandDescription, TabletopGrasp, load_embodiment
from sim.embodiment.frames import quat_to_mat
from sim.embodiment.mirror import mirror_vec
from sim.scene.builder import Scene
from teleop.operator_motion import (DURATIONS, NOT_IN_HAND_M, SideTimeline, axis_rotation, roll_then_swing,
                                    quat as motion_quat)
from teleop.plan_steps.fallback import plan_step
from teleop.plan_steps.park import rest_pos, wait_parked
from teleop.transit import hand_outline, bounding_box_points, obstacles, transit_height

CLOSED_FRACTION = 0.9         # actuators the grasp does not name: how far towards their far end
STAGGER_STEPS = 120           # the left hand starts later so the hands never meet over a target
IK_ITERS = 30                 # per control step, warm-started: the plan moves the wrist little per step
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


def step_objects(item: dict, objects) -> set[str]:
    """The ``objects`` a plan step names in any field ("<object>/<link>" names its object)."""
    values = [v for value in item.values() for v in (value if isinstance(value, list) else [value])]
    return {v.split("/")[0] for v in values if isinstance(v, str) and v.split("/")[0] in objects}


class ScriptedOperator:
    name = "scripted"

    def reset(self, scene: Scene, data: mujoco.MjData) -> None:
        self.scene = scene
        model = scene.model
        self.ctrl_home = scene.layout.home_ctrl.copy()
        self.sides = {}
        self.link_angles: dict[str, float] = {}     # where earlier `turn` steps leave each link (planned)
        self.held: dict = {}     # hand -> plan_steps.held.HeldObject: what a step left in it for its next step
        # where plan steps leave the objects they move (and on or in what), and the control step by
        # which: (step, name, pos, on)
        self.moves: list[tuple[int, str, np.ndarray, str | None]] = []
        self._leaving: list[tuple[str, np.ndarray, str | None]] = []   # the step being planned's, stamped at its end
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
            # a pick's thin_grasp: the hand file's targets for a thin object where it declares them
            thin = np.array([np.clip(grasp.thin_close.get(n.removeprefix(f"{side}_"), c), l, h)
                             for n, c, l, h in zip(lay.hand_actuators, closed, lo, hi)])
            q_home = self.ctrl_home[arm_ids]
            pos0, quat0 = kin.fk(q_home)
            start = STAGGER_STEPS if side == "left" else 0
            self.sides[side] = {"kin": kin, "arm_ids": arm_ids, "hand_ids": hand_ids, "open": open_,
                                "closed": closed, "thin_closed": thin, "group": group, "grasp_centre": grasp.centre,
                                "tabletop": hand.tabletop_grasp is not None, "hand": hand.name,
                                "heavy_side_hold": hand.heavy_side_hold, "round_pinch": hand.round_pinch,
                                "wrist_site_id": model.site(lay.wrist_site).id, "corrections": [], "reaims": [],
                                "looks": [], "q": q_home.copy(), "q_home": q_home.copy(),
                                "timeline": SideTimeline(pos0, quat0, open_, start),
                                "home": (pos0, quat0), "name": side}
        ends: list[int] = []         # each step's last control step
        rest_out: dict[str, float] = {}     # per hand: its last step's park_out_m
        for item in scene.task.demo_plan:
            # `hand: both` (sim/demo_plan.py BOTH_HANDS): both timelines start together, once both are free
            stepping = [s for n, s in self.sides.items() if item["hand"] in (n, BOTH_HANDS)]
            tls = [s["timeline"] for s in stepping]
            wait_until = max((ends[j] for j in item.get("after", [])), default=0)
            wait_until += round(item.get("wait_s", 0.0) * CONTROL_HZ)     # opt-in: a pause after those
            if len(tls) > 1:
                wait_until = max(wait_until, *(tl.end for tl in tls))
            out_m = item.get("park_out_m", 0.0)
            for side in stepping:
                # the hand holds still until those steps are done (opt-in: parked out of the other arm's way)
                wait_parked(self, data, side, out_m, wait_until)
                rest_out[side["name"]] = out_m
            plan_step(self, data, item, stepping)      # its kind's planner (a pick's fallback: fallback.py)
            ends.append(max(tl.end for tl in tls))
            self.moves += [(ends[-1], *left) for left in self._leaving]
            self._leaving = []
        for side in self.sides.values():
            rest = rest_pos(self, data, side, rest_out.get(side["name"], 0.0))   # home, or parked (its last step's)
            side["timeline"].add(DURATIONS["approach"], pos=rest, quat=side["home"][1], hand=side["open"])
        self.length = max(s["timeline"].end for s in self.sides.values()) + SETTLE_STEPS

    def object_pos(self, data, name) -> np.ndarray:
        """Where object ``name`` is now (world)."""
        return data.xpos[self.scene.object_body_ids[name]].copy()

    def leaves(self, name: str, pos: np.ndarray, on: str | None = None) -> None:
        """The plan step being planned leaves object ``name`` at rest with its centre at ``pos`` (world)
        by its end, on or in object ``on`` (None: the table)."""
        self._leaving.append((name, np.asarray(pos, float).copy(), on))

    def planned_place(self, data: mujoco.MjData, name: str, step: int) -> tuple[np.ndarray, str | None]:
        """Where object ``name`` is at control step ``step`` as planned, and what it is on or in: where
        the last step to move it by then left it, else where it is now."""
        done = [(pos, on) for end, n, pos, on in self.moves if n == name and end <= step]
        return done[-1] if done else (self.object_pos(data, name), None)

    def planned_by_arrival(self, side: dict, data: mujoco.MjData, name: str, approach: slice) -> np.ndarray:
        """Where the plan leaves object ``name`` by the time ``side``'s approach to it (its keyframes
        ``approach``, a look_again's) arrives: the kinematic stand-in for the look as the hand sets off."""
        return self.planned_place(data, name, side["timeline"].frames[approach.stop - 1].end_step)[0]

    def set_off(self, side: dict, data: mujoco.MjData, item: dict, duration: int, pos, quat=None, hand=None,
                carried: tuple[str, np.ndarray] | None = None, roll_first: bool = False) -> None:
        """Move the hand from its last keyframe to ``pos`` (``quat``, ``hand``) in ``duration`` steps,
        as ``SideTimeline.add``; when the straight move would pass too low over an object (where the
        plan has it when the move starts), first rise to a transit height, move across there, then
        come down (teleop/transit.py). ``carried``: the object held (its centre's offset from the
        wrist, world), which must clear the others too. ``roll_first``: the hand first rolls about its
        fingers (once risen, if it rises), then swings them round on its way (operator_motion.roll_then_swing)."""
        tl: SideTimeline = side["timeline"]
        last = tl.frames[-1]
        quat = last.quat if quat is None else np.asarray(quat, float)
        hand = last.hand if hand is None else np.asarray(hand, float)
        ids = self.scene.object_body_ids
        model, turned = self.scene.model, {}
        for link, angle in self.link_angles.items():       # links earlier `turn` steps swing round
            j = model.joint(link).id
            turned[int(model.jnt_bodyid[j])] = (data.xanchor[j].copy(), axis_rotation(
                data.xaxis[j], angle - float(data.qpos[model.jnt_qposadr[j]])))
        placed = {n: self.planned_place(data, n, tl.end) for n in ids}
        # not in the way: the objects the step names (what it takes hold of, where it puts it) and what
        # earlier steps left on or in them, which the hand comes down to anyway; what it carries
        mine = step_objects(item, ids) | ({carried[0]} if carried else set())
        mine |= {n for n, (_, on) in placed.items() if on in mine}
        in_way = [ob for n, b in ids.items() if n not in mine
                  for ob in obstacles(model, data, n, b, placed[n][0] - data.xpos[b], turned)]
        points = None
        if carried is not None:
            name, offset = carried
            points = bounding_box_points(self.scene.model, data, ids[name]) - data.xpos[ids[name]] + offset
        outline = hand_outline(side["hand"], side["name"], last.hand, hand)
        height = transit_height(last.pos, last.quat, np.asarray(pos, float), quat, outline, points, in_way)
        if height is None:
            self._roll(tl, quat, roll_first)
            tl.add(duration, pos=pos, quat=quat, hand=hand)
            return
        height = max(height, last.pos[2], float(pos[2]))
        if height > last.pos[2]:
            tl.add(DURATIONS["lift"], pos=np.array([*last.pos[:2], height]))
        self._roll(tl, quat, roll_first)
        tl.add(duration, pos=np.array([pos[0], pos[1], height]), quat=quat, hand=hand)
        if height > pos[2]:
            tl.add(DURATIONS["descend"], pos=pos)

    @staticmethod
    def _roll(tl: SideTimeline, quat: np.ndarray, roll_first: bool) -> None:
        """set_off's ``roll_first``: the roll about the fingers where the hand is, in two halves (the way round)."""
        if roll_first:
            for R in roll_then_swing(quat_to_mat(tl.frames[-1].quat), quat_to_mat(quat)):
                tl.add(DURATIONS["approach"] // 2, quat=motion_quat(R))

    def set_off_home(self, side: dict, data: mujoco.MjData, hand=None) -> None:
        """Take the hand back to where it rests (``hand``: its joints on the way, else as they are), over
        whatever is in the way (set_off): once a step is done, an arm left where it worked can meet the
        other arm's next step, and the pose it stretched into can leave the next step out of reach."""
        self.set_off(side, data, {"hand": side["name"]}, DURATIONS["approach"], pos=side["home"][0],
                     quat=side["home"][1], hand=hand)

    def look_again(self, side: dict, name: str, data, first: int, end: int, planned=None) -> None:
        """When the hand sets off towards ``name`` (the start of frame ``first``), the operator looks
        where it is now (an earlier step may have pushed or nudged it) and moves frames
        ``first``..``end`` with it (horizontally: heights come from the object's size); ``planned``:
        where those frames expect it (default: where it is while planning)."""
        planned = self.object_pos(data, name) if planned is None else np.asarray(planned, float)
        side["reaims"].append((side["timeline"].frames[first - 1].end_step, name, planned, slice(first, end)))

    @staticmethod
    def on_frame_end(side: dict, frame: int, adjust) -> None:
        """When frame ``frame`` ends the operator looks, and ``adjust(data)`` (the plan step's own)
        changes this step's later keyframes: e.g. a bottle turned in the hand while pouring is turned
        back upright by how it sits, not by how the hand was."""
        side["looks"].append((side["timeline"].frames[frame].end_step, adjust))

    def reaim(self, side: dict, data: mujoco.MjData, step: int, where: Callable | None = None) -> None:
        """The look as a hand sets off for an object: the frames of its approach move (level) with the
        object from where it was planned to where it is, in ``data``, or ``where(name, frames)`` (the
        kinematic dry run's stand-in: where the plan leaves it by then)."""
        while side["reaims"] and side["reaims"][0][0] <= step:
            _, name, planned, frames = side["reaims"].pop(0)
            moved = (self.object_pos(data, name) if where is None else where(name, frames)) - planned
            moved[2] = 0.0
            for frame in side["timeline"].frames[frames]:
                frame.pos = frame.pos + moved

    @staticmethod
    def power(side: dict, closure: tuple[float, float]) -> np.ndarray:
        """The side's power-grasp hand targets at ``closure`` (early, late actuators; 0 open .. 1 closed)."""
        c = np.asarray(closure, float)[side["group"]]
        return side["open"] + c * (side["closed"] - side["open"])

    def _correct_place(self, side: dict, data: mujoco.MjData, step: int) -> None:
        while side["corrections"] and side["corrections"][0][0] <= step:
            _, name, planned_offset, frames = side["corrections"].pop(0)
            wrist = data.site_xpos[side["wrist_site_id"]]
            error = (self.object_pos(data, name) - wrist) - planned_offset
            error[2] = 0.0      # height is set by the release gap
            if np.linalg.norm(error) > NOT_IN_HAND_M:     # nothing to correct for
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
            self.reaim(side, data, step)
            self._correct_place(side, data, step)
            while side["looks"] and side["looks"][0][0] <= step:     # a plan step's own look (on_frame_end)
                side["looks"].pop(0)[1](data)
            out[name] = side["timeline"].at(step)
        return out

    def act(self, step: int, data: mujoco.MjData) -> np.ndarray:
        ctrl = self.ctrl_home.copy()
        for name, (pos, quat, hand) in self.intent(step, data).items():
            side = self.sides[name]
            result = side["kin"].ik_tracking(pos, quat, side["q"], side["q_home"], max_iters=IK_ITERS)
            side["q"] = result.q
            ctrl[side["arm_ids"]] = result.q
            ctrl[side["hand_ids"]] = hand
        return ctrl

    def done(self, step: int) -> bool:
        return step >= self.length
