"""Plan step `turn`: swing a hinged link (a lid, a door) to a joint angle.

The way a person flips a bin lid open by its lip, or swings a door by its handle: the straight
fingers, tilted towards the hinge, come at the link's handle (its part reaching farthest from the
hinge) from the side it is to move away from, and push it round its arc about the hinge. As the
link turns, the fingertips slide along its face towards the hinge as far as the arm needs to keep
reaching (checked with the arm's IK while planning), and the hand turns with the link so that the
fingers keep pushing square to the face. At the target angle the hand draws back off the face, so
nothing drags the link back; a lid pushed past vertical falls open onto its limit, and the next
`turn` of the same link starts from where gravity leaves it.

Everything comes from the scene: the hinge's anchor and axis (world), the link's geometry (rays
against its parts find the face to push), the fingertips from the hand's kinematics; the opening
direction is the one away from the range end nearer joint zero (the link as modelled, shut).
A link centred on its hinge (a screen swivelling about its middle) is pushed at the free edge
whose face looks towards the hand. A link swinging towards the hand (a door opening outwards) is
pulled by its handle, a bar standing off its face: the fingers come down along the hinge axis into
the gap behind the bar and the pads draw it round; shutting it again from in front, the fingers come
down in front of the bar the same way and push it back. With `palm_from` (opt-in) the fingers lie
along the hinge all the way and from that angle on the flat palm pushes (teleop/plan_steps/palm_push.py).
A lid let go below vertical at that handoff falls back; with `palm_look` (opt-in) the hand backs well off,
and the operator looks where the link is as the hand moves in under it, comes up to it and presses, and
turns the palm's keyframes about the hinge to it (`palm_look`).
With `start_look` (opt-in) the turn starts from where the link really is: planned from where earlier steps leave
it, its keyframes turn about the hinge as the hand sets off and again as it comes down to the face: those planned
short of a link that stopped short come to it and the push goes on from there as planned (a lever that slipped off
the fingers short of its planned angle is shut from where it stopped, not swept past from where the opening meant
to leave it); a link beyond the planned start is pushed from there, the push spread over the same steps.
With `withdraw_past_end` (opt-in) the hand, once it lets go, moves level out along the link past its free end
and goes on from there, rather than rising over the link (the arm behind it would lie across a tall door's top);
with home on the link's other side it first turns round that end, past it, until it is wholly on home's side
(straight home from past the end, the fingers crossed a door pulled open past square and shoved it back).
With `roll_first` (opt-in) the hand, before it sets off, rolls about its fingers where it is to the turn's roll and
then swings them round on its way: turned over from a palm push (thumb up) to a lever pushed thumb down, half a turn
about a level axis in one move, the UR5's wrist_1 folded the wrist onto its forearm (the IK's branch from there);
rolled first, the last wrist joint takes the half turn.
With `plan_from` (opt-in) the turn is planned from that angle, not from where earlier steps leave the link: a second
shut of a door a first shut, reaching over it at its widest, may leave ajar (the plan has it shut, so a plain second
turn plans nothing); with `start_look` the hand meets the door where it really is, and pushes nothing if it is shut.
"""

from __future__ import annotations


import mujoco
import numpy as np

from sim.embodiment.frames import quat_to_mat
from sim.embodiment.mirror import mirror_vec
from sim.errors import SpecError
from sim.physics import CONTROL_HZ
from teleop.geom_rays import nearest_hit
from teleop.operator_motion import APPROACH_HEIGHT_M, DURATIONS, UP, SideTimeline, axis_rotation, quat
from teleop.pinch_grasp import fingertip_rows, fingertips_in_site_frame
from teleop.plan_steps.operator import PlanningOperator
from teleop.plan_steps.palm_push import PALM_REACH, finger_tips, innermost, palm_frame, palm_point, palm_turns
from teleop.transit import CLEARANCE_M, hand_outline


TILTS_DEG = (45.0, 30.0, 15.0, 0.0)  # fingers tilted from the push direction towards the hinge: at first the tips
                                     # lead, under a lip; straighter later where the arm reaches no further
PUSHING_TIPS = ("index_tip", "middle_tip")   # the pads that push (retarget keypoints they follow)
PUSH_DEPTH_M = 0.004          # fingertip pads aimed this far into the face: they press on it
FACE_GAP_M = 0.025            # ... and set down this far off it before pushing
ARC_STEP_RAD = 0.1            # keyframes this far apart along the arc
ARC_SPEED_M_PER_STEP = 0.0015  # the contact's speed along the arc: 0.09 m/s (a step's `speed` overrides it)
# contact radii tried, as fractions of the handle centre's (outermost first): the tips start under the
# handle's outer half, clear of what it stands out from
RADIUS_FRACTIONS = np.linspace(1.03, 0.35, 18)
REACH_TOL_M = 0.008           # a wrist target the IK comes this close to is reached
IK_PASSES, IK_ITERS = 3, 30   # IK solves per arc point when checking the reach (the operator's: 30 a step)
GRAVITY_TORQUE_NM = 1e-3      # below this the link stays where it is let go (a door on a vertical hinge)
RAY_BACKOFF_M = 0.3           # rays start this far off the link, on the pushing side
PULL_AHEAD_M = 0.1            # a hand resting this far ahead of the face the link swings towards pulls it (below)
UPRIGHT_AXIS_COS = 0.5        # a hinge axis within 60 degrees of vertical is upright (a door's): pulling fingers point down
LOOK_BACK_OFF_M = 0.1         # with palm_look the fingertips back this far off the face: clear of the link as it falls back
LOOKS = 3                     # palm_look: the operator looks as the hand sets off under the face, up to it, and presses
EDGE_TOL_M = 0.01             # corners of the handle part this close to its farthest reach make up a free edge
ROUND_STEP_RAD = 0.1          # withdraw_past_end: the hand goes round the link's free end in keyframes this far apart
ROUND_MAX_RAD = 1.6           # ... and at most this far round the hinge


def plan(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    link = Hinge(op.scene.model, data, item["turn"], op.scene.task.source)
    start = op.link_angles.get(item["turn"], link.angle)
    if item.get("plan_from") is not None:       # opt-in: planned from this angle (a re-shut: see the docstring)
        start = float(item["plan_from"])
    target = float(item["to"])
    # opt-in `speed` (m/s of the contact along the arc): a door swung as briskly as a person swings it
    arc_step_m = item["speed"] / CONTROL_HZ if "speed" in item else ARC_SPEED_M_PER_STEP
    if abs(target - start) < 1e-6:
        return
    way = np.sign(target - start)               # +1: the way the joint angle grows
    link.choose_edge(way, side["home"][0])
    tips = fingertips_in_site_frame(side["hand"], side["open"])[fingertip_rows(side["hand"], PUSHING_TIPS)]
    tip = tips.mean(axis=0)
    tip = mirror_vec(tip) if item["hand"] == "left" else tip
    n = max(1, int(np.ceil(abs(target - start) / ARC_STEP_RAD)))
    arc = np.linspace(start, target, n + 1)
    # a link swinging towards the hand (a door opening outwards): reaching round behind it the arm
    # would fold back on itself, so the fingers come down along the hinge axis behind the handle
    # (a bar standing off the face) and the pads pull it round
    handle = link.rotated(link.handle, start - link.angle)     # where an earlier turn left it
    pull = float(way * link.tangent(handle) @ (side["home"][0] - handle)) > PULL_AHEAD_M
    palm_from = item.get("palm_from")     # opt-in: the fingers along the axis all the way, the palm pushing from this angle on
    along_axis = pull or palm_from is not None
    faces = link.faces(way, start, handle_only=pull)   # contact radius -> face point (world, at ``start``)
    # fingers along the axis: downwards, reaching over the handle (or, the axis level, away from the hand)
    above = link.axis @ UP if abs(link.axis @ UP) > UPRIGHT_AXIS_COS else link.axis @ (side["home"][0] - handle)
    down = -link.axis * np.sign(above)
    tilt_choices = TILTS_DEG[:1] if along_axis else TILTS_DEG     # fingers along the axis: no tilt to try
    if palm_from is not None:
        palm = palm_point(side["hand"], item["hand"], side["open"])     # teleop/plan_steps/palm_push.py
        fingers = finger_tips(side["hand"], item["hand"], side["open"])

    def pose(angle: float, radius: float, tilt: float, gap: float = -PUSH_DEPTH_M) -> tuple[np.ndarray, np.ndarray]:
        face = link.rotated(faces[radius], angle - start)
        push = way * link.tangent(face)          # where the face moves as the link turns ``way``
        if palm_turns(angle, palm_from, way):
            R = palm_frame(push, down)
            return face - gap * push - R @ palm, R
        inward = -link.radial(face)
        a = np.radians(tilt)
        z = np.cos(a) * push + np.sin(a) * inward              # fingers
        if along_axis:
            z, y = down, push                    # fingers down behind the handle, the pads facing the way they pull
        else:
            y = inward - (inward @ z) * z if tilt > 0 else -link.axis * way   # palm towards the hinge (or along it, square)
        y /= np.linalg.norm(y)
        R = np.column_stack([np.cross(y, z), y, z])
        if palm_from is not None:       # the fingertip nearest the hinge under the edge, the others beyond it
            return face - gap * push - R @ innermost(fingers, R, link.radial(face)), R
        return face - gap * push - R @ tip, R

    # along the arc, the outermost contact and the most tilted fingers the arm reaches, neither ever
    # going back (the fingertips slide in along the face and straighten up against it as it turns)
    kin, q = side["kin"], side["q"].copy()
    radii, tilts, choices = [], [], sorted(faces, reverse=True)
    pos, R = pose(start, choices[0], tilt_choices[0], FACE_GAP_M)
    q = _solve(kin, pos + APPROACH_HEIGHT_M * link.radial(faces[choices[0]]), R, q)
    for angle in arc:
        found = None
        for radius in [r for r in choices if (not radii or r <= radii[-1])
                       and (not palm_turns(angle, palm_from, way) or r <= PALM_REACH * link.handle_radius)]:
            for tilt in [t for t in tilt_choices if not tilts or t <= tilts[-1]]:
                pos, R = pose(angle, radius, tilt)
                q_try = _solve(kin, pos, R, q)
                if np.linalg.norm(kin.fk(q_try)[0] - pos) <= REACH_TOL_M:
                    found, q = (radius, tilt), q_try
                    break
            if found:
                break
        if found is None:           # out of reach: push on as the last reached pose did, as far as the arm goes
            found = (radii[-1], tilts[-1]) if radii else (choices[0], tilt_choices[0])
        radii.append(found[0])
        tilts.append(found[1])
    first = pose(start, radii[0], tilts[0], FACE_GAP_M)
    back = -first[1][:, 2] if along_axis else link.radial(faces[radii[0]])   # in along the fingers, or from beyond the free edge
    if palm_from is not None and not pull:      # ... a push along the axis: both, clear of what the link stands on
        back = (back + link.radial(faces[radii[0]])) / np.linalg.norm(back + link.radial(faces[radii[0]]))
    approach = first[0] + APPROACH_HEIGHT_M * back
    step_first = len(tl.frames)         # this step's first keyframe
    if item.get("approach_over", False):
        # opt-in: first to above the link's top, over whatever is in the way, the link included (a door pulled
        # open past square stands between the hand and its outer side, where its bar is), then down to it
        lowest = float(np.min((hand_outline(side["hand"], item["hand"], side["open"]) @ first[1].T)[:, 2]))
        above = approach.copy()
        above[2] = max(approach[2], link.top(start) + CLEARANCE_M - lowest)
        op.set_off(side, data, {"hand": item["hand"]}, DURATIONS["approach"], pos=above, quat=quat(first[1]),
                   hand=side["open"], roll_first=item.get("roll_first", False))
        tl.add(DURATIONS["descend"], pos=approach)
    else:
        op.set_off(side, data, item, DURATIONS["approach"], pos=approach, quat=quat(first[1]), hand=side["open"],
                   roll_first=item.get("roll_first", False))
    approached = len(tl.frames) - 1     # the hand off the face, where it comes down from
    tl.add(DURATIONS["descend"], pos=first[0])
    previous, previous_angle, previous_R = (faces[radii[0]], first[0]), start, first[1]
    palm_frames: dict[int, float] = {}      # timeline frame -> the link angle its palm pose was planned for
    # start_look: every keyframe fixed to the link, from the approach on (timeline frame -> its link angle)
    link_frames: dict[int, float] = {approached: start, approached + 1: start}
    for angle, radius, tilt in zip(arc, radii, tilts):
        pos, R = pose(angle, radius, tilt)
        face = link.rotated(faces[radius], angle - start)
        moved = max(np.linalg.norm(face - previous[0]), np.linalg.norm(pos - previous[1]))
        steps = max(1, int(np.ceil(moved / arc_step_m)))
        if palm_turns(angle, palm_from, way) and not palm_turns(previous_angle, palm_from, way):
            # from fingertips onto the palm: the hand first backs off the face until the palm (which stands
            # higher off the hand than the fingertip pads) is clear of it, comes in just off the face, then presses
            back_off = FACE_GAP_M + max(0.0, palm[1] - float(fingers[:, 1].min()))
            if item.get("palm_look", False):
                # the link falls back as the fingertips let go: the hand backs well off, moves in under the
                # face there, then comes up to it where the operator sees it (palm_look below)
                back_off = max(back_off, LOOK_BACK_OFF_M)
                tl.add(DURATIONS["open"], pos=previous[1] - back_off * previous_R[:, 1])
                link_frames[len(tl.frames) - 1] = previous_angle
                tl.add(DURATIONS["open"], pos=pose(angle, radius, tilt, back_off)[0], quat=quat(R))
                palm_frames[len(tl.frames) - 1] = angle
            else:
                tl.add(DURATIONS["open"], pos=previous[1] - back_off * previous_R[:, 1])
                link_frames[len(tl.frames) - 1] = previous_angle
            tl.add(DURATIONS["descend"], pos=pose(angle, radius, tilt, FACE_GAP_M)[0], quat=quat(R))
            palm_frames[len(tl.frames) - 1] = angle
        previous_angle, previous_R = angle, R
        tl.add(steps, pos=pos, quat=quat(R))
        if palm_turns(angle, palm_from, way):
            palm_frames[len(tl.frames) - 1] = angle
        link_frames[len(tl.frames) - 1] = angle
        previous = (face, pos)
    looked = palm_frames            # the frames the looks turn about the hinge
    if item.get("start_look", False):
        # opt-in: the operator looks where the link is as the hand sets off and as it comes down to the face, and
        # the turn starts from there (the frames taking the hand over to above the approach move with it)
        looked = {**link_frames, **palm_frames}
        follow = [i for i in range(step_first, approached) if np.allclose(tl.frames[i].pos[:2], approach[:2])]
        op.on_frame_end(side, step_first - 1, start_look(op, side, link, item["turn"], looked, target, approached,
                                                         follow))
        op.on_frame_end(side, approached, start_look(op, side, link, item["turn"], looked, target, approached + 1))
    if palm_frames and item.get("palm_look", False):
        # opt-in: as the fingertips back off for the palm, the operator looks where the link is (let go, a lid
        # falls back some way) and the palm comes in at it rather than at the planned angle
        for frame in sorted(palm_frames)[:LOOKS]:
            op.on_frame_end(side, frame - 1, palm_look(op, side, link, item["turn"], looked, target, frame))
    # draw back off the face the way the fingers came (a palm: straight off it), then rise clear of
    # the link and what it is on
    pos = pos - APPROACH_HEIGHT_M * (R[:, 1] if palm_turns(arc[-1], palm_from, way) else R[:, 2])
    tl.add(DURATIONS["retreat"], pos=pos)
    if item.get("withdraw_past_end", False):
        # opt-in: out along the link, level, until the whole hand is past its free end, and home from there round
        # that end: a hand rising over a tall door it pulled open leaves the arm behind it across the door's top
        # (the way home then shoved the door back)
        out = link.radial(link.rotated(faces[radii[-1]], arc[-1] - start))
        inner = float(np.min(hand_outline(side["hand"], item["hand"], side["open"]) @ R.T @ out))
        beyond = link.reach() + CLEARANCE_M - float(link.radial_vec(pos) @ out) - inner
        pos = pos + max(0.0, beyond) * out
        tl.add(DURATIONS["lift"], pos=pos)
        # the hand pulled from the side the link swings to, or pushed from the other
        hand_side = way if pull else -way
        for pos_round, R_round, steps in round_end(link, target, out, hand_side, side, item["hand"], pos, R, arc_step_m):
            tl.add(steps, pos=pos_round, quat=quat(R_round))
    else:
        tl.add(DURATIONS["lift"], pos=pos + APPROACH_HEIGHT_M * UP)
    # back to where the hand rests: the arm leaves the pose it stretched into around the link; unless
    # `return_home: false`: the hand waits where it rose off the link, and its next step sets off from there
    op.link_angles[item["turn"]] = link.rest_angle(target)
    if item.get("return_home", True):
        # over whatever is in the way, the link as it was left included (a tall door pulled open past
        # square stands between the hand and home: teleop/transit.py)
        op.set_off_home(side, data)


def round_end(link: "Hinge", angle: float, out: np.ndarray, hand_side: float, side: dict, hand: str,
              pos: np.ndarray, R: np.ndarray, step_m: float) -> list[tuple[np.ndarray, np.ndarray, int]]:
    """With `withdraw_past_end`: the keyframes (wrist, hand frame, steps) that take the hand, past the free end
    of ``link`` (at joint ``angle``, reaching along ``out`` from its hinge) at
    ``pos``, on the link's ``hand_side`` (+1: the side its points move to as the joint grows), round that end
    to the other side when home lies there, turning with it about the hinge (every point of the hand stays
    as far from the axis, all past the end), until the whole hand is CLEARANCE_M beyond the link on that
    side; none when home is on the hand's side. From there the way home does not cross the link (a door
    pulled open past square, between the hand and home)."""
    corners = link.corners(angle)
    normal = np.cross(link.axis, out)           # off the plane through the hinge and ``out``: hand_side +1
    home_side = np.sign(float(normal @ (side["home"][0] - link.anchor)))
    if home_side == hand_side:
        return []
    face = float(np.max(home_side * (corners - link.anchor) @ normal))   # how far the link reaches on home's side
    outline = hand_outline(side["hand"], hand, side["open"])
    steps = max(1, int(np.ceil(ROUND_STEP_RAD * np.linalg.norm(link.radial_vec(pos)) / step_m)))   # each keyframe's
    frames, rounded = [], 0.0
    while rounded < ROUND_MAX_RAD:
        rounded += ROUND_STEP_RAD
        turn = axis_rotation(link.axis, home_side * rounded)
        wrist, R_now = link.anchor + turn @ (pos - link.anchor), turn @ R
        frames.append((wrist, R_now, steps))
        if np.min(home_side * (wrist + outline @ R_now.T - link.anchor) @ normal) >= face + CLEARANCE_M:
            break
    return frames


def palm_look(op: PlanningOperator, side: dict, link: "Hinge", joint: str, palm_frames: dict[int, float],
              target: float, first: int):
    """The look when the palm takes over a turn: ``palm_frames`` (timeline frame -> link angle it was
    planned for) turn about the hinge with the link, the first to the link's angle now and the rest spread
    from there to ``target`` over the same steps (a palm pose is fixed to the link: fingers along the
    hinge, the palm square to the face)."""
    adr = op.scene.model.jnt_qposadr[op.scene.model.joint(joint).id]

    def look_at_link(data: mujoco.MjData) -> None:
        _respread(side["timeline"].frames, link, palm_frames, target, first, float(data.qpos[adr]))
    return look_at_link


def start_look(op: PlanningOperator, side: dict, link: "Hinge", joint: str, link_frames: dict[int, float],
               target: float, first: int, follow: list[int] = ()):
    """The look with `start_look`, at the end of the frame before ``first``: ``link_frames`` (timeline frame ->
    link angle it was planned for, all fixed to the link) from ``first`` on turn about the hinge. A link short of
    the angle ``first`` was planned for (between it and ``target``: it slipped back from an opening) is met where
    it is: the frames planned short of it come to it and the push goes on from there as planned (the poses the
    plan checked the arm reaches; spreading the whole push over the shorter arc, the fingers lagged the lever 0.1
    rad and left it open); a link beyond it is pushed from there, the frames spread from it to ``target``. A link
    already at or past ``target`` is taken as at it (nothing left to push). Frames ``follow`` (the hand's way over
    to ``first``, above it) move level with ``first``. In the kinematic dry run (teleop/cross_embodiment.py) no
    look runs: the turn is tracked from where the plan leaves the link."""
    adr = op.scene.model.jnt_qposadr[op.scene.model.joint(joint).id]

    def look_where_the_link_is(data: mujoco.MjData) -> None:
        frames = side["timeline"].frames
        now, ref = float(data.qpos[adr]), link_frames[first]
        if (target - now) * (target - ref) <= 0.0:
            now = target
        before = frames[first].pos.copy()
        turn = _respread(frames, link, link_frames, target, first, now,
                         passed_only=(now - target) * (ref - now) >= 0.0)
        if turn is None:
            return
        moved = frames[first].pos - before
        for i in follow:
            frames[i].pos = np.array([*(frames[i].pos[:2] + moved[:2]), max(frames[i].pos[2], frames[first].pos[2])])
            frames[i].quat = quat(turn @ quat_to_mat(frames[i].quat))
    return look_where_the_link_is


def _respread(frames: list, link: "Hinge", angles: dict[int, float], target: float, first: int,
              now: float, passed_only: bool = False) -> np.ndarray | None:
    """Turn keyframes ``frames[i]`` for ``angles`` (i -> the link angle each was planned for) from ``first`` on
    about the hinge: the first to ``now``, the rest spread from there to ``target`` over the same steps, or with
    ``passed_only`` (``now`` between the first's angle and ``target``) only those planned short of ``now`` come to
    it and the rest stay as planned; ``angles`` is updated. Returns the first's turn (None when the first was
    planned at ``target``)."""
    ref = angles[first]
    if abs(target - ref) < 1e-9:
        return None
    first_turn = None
    for i, planned in [(i, a) for i, a in angles.items() if i >= first]:
        if passed_only:
            delta = now - planned if (planned - now) * (ref - target) > 0.0 else 0.0
        else:
            delta = now + (planned - ref) * (target - now) / (target - ref) - planned
        turn = axis_rotation(link.axis, delta)
        frames[i].pos = link.anchor + turn @ (frames[i].pos - link.anchor)
        frames[i].quat = quat(turn @ quat_to_mat(frames[i].quat))
        angles[i] = planned + delta
        first_turn = turn if i == first else first_turn
    return first_turn


def _solve(kin, pos: np.ndarray, R: np.ndarray, q: np.ndarray) -> np.ndarray:
    for _ in range(IK_PASSES):
        q = kin.ik(pos, quat(R), q, max_iters=IK_ITERS).q
    return q


class Hinge:
    """A hinged link as the scene has it now: anchor and axis (world), angle, range, and its handle
    (the part reaching farthest from the hinge)."""

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, name: str, source="demo_plan"):
        self.model, self.data, self.source = model, data, source
        joint = model.joint(name)
        if joint.type[0] != mujoco.mjtJoint.mjJNT_HINGE:
            raise SpecError(source, "demo_plan.turn", "a hinge-jointed link", name)
        self.body = int(joint.bodyid[0])
        self.anchor = data.xanchor[joint.id].copy()
        self.axis = data.xaxis[joint.id] / np.linalg.norm(data.xaxis[joint.id])
        self.angle = float(data.qpos[model.jnt_qposadr[joint.id]])
        self.range = tuple(float(v) for v in model.jnt_range[joint.id])
        self.geoms = range(model.body_geomadr[self.body], model.body_geomadr[self.body] + model.body_geomnum[self.body])
        reach = {g: max(np.linalg.norm(self.radial_vec(c)) for c in self._corners(g)) for g in self.geoms}
        self.handle_geom = max(reach, key=reach.get)
        self.handle = data.geom_xpos[self.handle_geom].copy()
        self.handle_radius = float(np.linalg.norm(self.radial_vec(self.handle)))

    def choose_edge(self, way: float, hand: np.ndarray) -> None:
        """A part that spans its hinge (a screen swivelling about its middle) has no handle out on one
        side: its centre is near the axis and it has a free edge on either side. Take as the handle
        the middle of the free edge whose pushed face looks towards the hand at ``hand`` (world), so
        the fingers come at it without reaching round the link. A part out on one side (a lid's
        tab) keeps its centre."""
        corners = self._corners(self.handle_geom)
        reach = np.array([np.linalg.norm(self.radial_vec(c)) for c in corners])
        if self.handle_radius >= 0.5 * reach.max():
            return
        edges = []
        for far in (corners[int(np.argmax(reach))], None):
            if far is None:             # the far edge on the other side of the axis from the first
                away = [i for i, c in enumerate(corners) if self.radial_vec(c) @ self.radial_vec(edges[0]) < 0]
                if not away:
                    break
                far = corners[max(away, key=lambda i: reach[i])]
            edge = [c for c in corners if self.radial_vec(c) @ self.radial_vec(far) > 0
                    and np.linalg.norm(self.radial_vec(c)) >= np.linalg.norm(self.radial_vec(far)) - EDGE_TOL_M]
            edges.append(np.mean(edge, axis=0))
        # the pushed face looks against the push: the hand should be on that side of the edge
        self.handle = max(edges, key=lambda e: float(-way * self.tangent(e) @ (hand - e)))
        self.handle_radius = float(np.linalg.norm(self.radial_vec(self.handle)))

    def reach(self) -> float:
        """How far the link reaches from its hinge axis (its farthest corner)."""
        return max(float(np.linalg.norm(self.radial_vec(c))) for g in self.geoms for c in self._corners(g))

    def top(self, angle: float) -> float:
        """The link's highest point (world z) at joint ``angle``."""
        return float(self.corners(angle)[:, 2].max())

    def corners(self, angle: float) -> np.ndarray:
        """[K, 3] world corners of the link's geoms' boxes at joint ``angle``."""
        return np.array([self.rotated(c, angle - self.angle) for g in self.geoms for c in self._corners(g)])

    def radial_vec(self, p: np.ndarray) -> np.ndarray:
        """From the hinge axis to ``p``, perpendicular to it."""
        d = p - self.anchor
        return d - (d @ self.axis) * self.axis

    def radial(self, p: np.ndarray) -> np.ndarray:
        r = self.radial_vec(p)
        return r / np.linalg.norm(r)

    def tangent(self, p: np.ndarray) -> np.ndarray:
        """The unit direction point ``p`` of the link moves in as the joint angle grows."""
        return np.cross(self.axis, self.radial(p))

    def rotated(self, p: np.ndarray, angle: float) -> np.ndarray:
        """Point ``p`` of the link after the joint turns by ``angle``."""
        return self.anchor + axis_rotation(self.axis, angle) @ (p - self.anchor)

    def faces(self, way: float, start: float, handle_only: bool = False) -> dict[float, np.ndarray]:
        """The link's face on the side it is pushed from, at contact radii (RADIUS_FRACTIONS of the
        handle's) along the handle's radial line and at the link angle ``start``: rays towards the
        link against its own parts. Radii whose ray misses the link are left out. ``handle_only``:
        rays against the handle alone, finding the side of a bar standing off the link that fingers
        hooked behind it pull on."""
        turn = start - self.angle
        out = {}
        for f in RADIUS_FRACTIONS:
            along = self.handle - (self.radial_vec(self.handle)) * (1.0 - f)
            push = way * self.tangent(along)
            origin = along - RAY_BACKOFF_M * push
            d = nearest_hit(self.model, self.data, [self.handle_geom] if handle_only else self.geoms, origin, push)
            if d is not None:
                out[float(f * self.handle_radius)] = self.rotated(origin + d * push, turn)
        if not out:
            raise SpecError(self.source, "demo_plan.turn", "a link with a face to push",
                            self.model.body(self.body).name)
        return out

    def rest_angle(self, angle: float) -> float:
        """Where the link settles when let go at ``angle``: on the limit gravity turns it towards, or
        where it is if gravity has no hold on it."""
        com = self.rotated(self.data.subtree_com[self.body], angle - self.angle)   # with any child links
        weight = self.model.body_subtreemass[self.body] * self.model.opt.gravity
        torque = float(np.cross(com - self.anchor, weight) @ self.axis)
        if abs(torque) < GRAVITY_TORQUE_NM:
            return angle
        return self.range[1] if torque > 0 else self.range[0]

    def _half_extents(self, g: int) -> np.ndarray:
        size, kind = self.model.geom_size[g], self.model.geom_type[g]
        if kind == mujoco.mjtGeom.mjGEOM_BOX or kind == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
            return size.copy()
        if kind == mujoco.mjtGeom.mjGEOM_CYLINDER:
            return np.array([size[0], size[0], size[1]])
        if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
            return np.array([size[0], size[0], size[1] + size[0]])
        return np.full(3, self.model.geom_rbound[g])

    def _corners(self, g: int) -> list[np.ndarray]:
        half, R = self._half_extents(g), self.data.geom_xmat[g].reshape(3, 3)
        return [self.data.geom_xpos[g] + R @ (half * (2 * np.array(s) - 1)) for s in np.ndindex(2, 2, 2)]
