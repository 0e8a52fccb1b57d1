"""The `turn` step kind's schema."""

from __future__ import annotations

from pydantic import Field, ValidationInfo, field_validator

from ..base import Bool, Name, Number, is_number
from .fields import TURN_SPEED_RANGE_M_S, hinge_ranges, one_of
from .step import PlanStep


class TurnStep(PlanStep):
    """{hand, turn: <object>/<link>, to: <angle, rad>, [palm_from], [palm_look], [start_look], [speed], [return_home],
    [approach_over], [withdraw_past_end], [roll_first], [plan_from], [after], [wait_s]}: swing a
    hinge-jointed link (a lid, a door) to an angle within its joint range; from the link angle palm_from
    on (rad, within the range) the flat palm pushes, fingers along the hinge, instead of the fingertips;
    palm_look: true (with palm_from) re-aims the palm at the link's angle as the fingertips let go of it;
    start_look: true starts the turn from the link's angle as the hand sets off and as it comes down to it (planned
    from where earlier steps leave it): its keyframes turn about the hinge to it;
    speed (m/s) is how fast the hand's contact moves along the arc (default 0.09); return_home: false leaves
    the hand risen off the link where it let go, so the next step sets off from there; approach_over: true
    brings the hand to the link from above its top; withdraw_past_end: true takes the hand, once it lets go,
    out along the link past its free end before it goes on (round that end, not over the link: with home on the
    link's other side, round the end to that side first); roll_first: true has the hand, before it sets off, roll
    about its fingers where it is to the turn's roll, then swing them round on its way; plan_from (rad, within the
    range) plans the turn from that angle rather than from where earlier steps leave the link (with start_look: a
    re-shut of a door an earlier turn meant to shut, met where it really stopped)."""

    turn: Name
    to: Number
    palm_from: Number = None
    # true: as the palm takes over, the operator looks where the link is (let go, it falls back) and pushes it from there
    palm_look: Bool = False
    # true: the turn starts from where the link is as the hand sets off for it, not where earlier steps meant to
    # leave it (a lever that slipped out of the pulling fingers short of its angle, shut again from there)
    start_look: Bool = False
    speed: Number = Field(None, gt=TURN_SPEED_RANGE_M_S[0], le=TURN_SPEED_RANGE_M_S[1],
                          description=f"m/s of the contact along the arc in ({TURN_SPEED_RANGE_M_S[0]:g}, "
                                      f"{TURN_SPEED_RANGE_M_S[1]:g}]")
    # false: the hand stays where it rose off the link (a tall door pulled open stands between it and home)
    return_home: Bool = True
    # true: the hand comes to the link from above its top (a door pulled open past square, shut again from its
    # outer side: the hand rises over it rather than through it)
    approach_over: Bool = False
    # true: after letting go the hand moves out along the link past its free end, and goes on from there round
    # that end rather than rising over the link (the arm behind a hand outside a tall door lies across its top);
    # home on the link's other side, it turns round the end to that side before it goes home
    withdraw_past_end: Bool = False
    # true: the hand first rolls about its fingers where it is, then swings them round on its way to the link (from a
    # palm push, thumb up, to a lever pushed thumb down: turned over in one move the UR5's wrist folded onto its forearm)
    roll_first: Bool = False
    # an angle: the turn is planned from it, not from where earlier steps leave the link (a second shut of a door the
    # first may leave ajar; with start_look the hand meets the door where it is, nothing left to push if it is shut)
    plan_from: Number = None

    @field_validator("turn", mode="before")
    @classmethod
    def _a_hinge(cls, link: str, info: ValidationInfo) -> str:
        hinges = hinge_ranges(info)
        return one_of(link, hinges, f"a hinge-jointed link from {sorted(hinges)}")

    @field_validator("to", "palm_from", "plan_from", mode="before")
    @classmethod
    def _within_the_range(cls, angle, info: ValidationInfo):
        link = info.data.get("turn")
        if link is None:                 # refused above already
            return angle
        lo, hi = hinge_ranges(info)[link]
        if not is_number(angle) or not lo <= angle <= hi:
            raise ValueError(f"an angle in rad within the joint range [{lo:g}, {hi:g}]")
        return angle
