"""A look at how a carried object sits in the hand before it is set down, as a person turns a leaning
bottle upright by the bottle itself: the hand turns by what the object's up is off vertical, and the
set-down keyframes move with the object's new place in the hand, so it goes down upright where planned.

front_place looks outside the opening (a bottle handed over hangs in the hand as the giver let it go);
pour after turning the pourer back and via after a swing (held from the side, it turns in the grip).
"""

from __future__ import annotations

import mujoco
import numpy as np

from teleop.operator_motion import NOT_IN_HAND_M, UP, axis_rotation, quat
from teleop.plan_steps.operator import PlanningOperator


def upright_look(op: PlanningOperator, side: dict, name: str, up_local: np.ndarray, hand_rot: np.ndarray,
                 offset: np.ndarray, frames: range, *, recentre_when_upright: bool, turn: bool = True):
    """The look, to run at a frame's end: ``up_local`` is the object's up (its frame), ``hand_rot`` the hand's
    planned rotation and ``offset`` the object's centre from the wrist (world) for which ``frames`` were
    planned; ``offset`` is updated to the new hold (a later slip correction measures against it). An object
    already upright (or upside down: no axis to turn about) keeps the planned turn, and its frames move for
    where it sits only if ``recentre_when_upright``. ``turn=False``: the hand keeps the planned turn whatever
    the object's lean, and the frames move for where it sits (an object with no up, a banana rolled in the grip)."""
    def adjust(data: mujoco.MjData) -> None:
        body = op.scene.object_body_ids[name]
        wrist_rot = data.site_xmat[side["wrist_site_id"]].reshape(3, 3)
        at = wrist_rot.T @ (data.xpos[body] - data.site_xpos[side["wrist_site_id"]])      # wrist frame
        if np.linalg.norm(at) > np.linalg.norm(offset) + NOT_IN_HAND_M:      # not in the hand any more
            return
        up = hand_rot @ (wrist_rot.T @ data.xmat[body].reshape(3, 3)) @ up_local    # its up, the hand as planned
        axis = np.cross(up, UP) if turn else np.zeros(3)
        if np.linalg.norm(axis) > 1e-9:
            angle = float(np.arctan2(np.linalg.norm(axis), up @ UP))
            rot = axis_rotation(axis / np.linalg.norm(axis), angle) @ hand_rot
        elif recentre_when_upright:
            rot = hand_rot
        else:
            return
        moved = offset - rot @ at           # each keyframe was the wrist for `offset`; now for the new hold
        for frame in side["timeline"].frames[frames.start:frames.stop]:
            frame.pos, frame.quat = frame.pos + moved, quat(rot)
        offset[:] = rot @ at
    return adjust
