"""The scripted operator through the person's stream interface: it plays the person.

Each control step the plan (``ScriptedOperator.intent``: wrist-site pose and hand actuator targets
per side, from the task's ``demo_plan``) is turned into what a person's devices would deliver, one
``OperatorFrame``, and that frame takes the live session's path: ``StreamSanitizer`` ->
``TeleopCommander`` (DexPilot per hand + the arm's CLIK) -> one absolute joint command, with the
step's flags and reasons. Nothing drives the joints directly.

Wrist: the operator's tracker frame is chosen equal to the robot's world frame and the operator's
wrist is where the robot's hand BASE should be, ``T_site @ site_in_base^-1``. The first frame
after reset is the commander's anchor; it is the home pose (the plan starts at home), so the
commander's ``base_home @ (anchor^-1 @ wrist) @ site_in_base`` lands the wrist site on the plan.
Where the plan's pose is out of the arm's reach (a joint limit on the way: the iiwa7 falls up to
56 mm short on some approaches) a person sees the robot wrist stop and does not drag their own
further away; they move on with the pose the arm does reach closest to the plan. The operator
finds that pose with the arm's IK warm-started from the previous one (as the direct joint path
does) and shows it instead. Otherwise the commander, rightly, holds the arm at the last reachable
pose, flags the step and jumps up to 80 mm in one step once the plan is reachable again.

Hand: a teleoperator watches the robot hand and shapes their own until the robot's fingertips are
where the grasp needs them. So the keypoint fingertips are the robot's fingertips at the intended
joint targets (forward kinematics of the retargeter's own hand model), relative to its wrist point
and divided by the retarget scale; DexPilot then finds those targets again, exactly on hands
whose fingertips fix their joints (at most 3 per fingertip). On the others (allegro, leap, orca,
shadow, sharpa, wuji) the fingertips still land within 1 mm but DexPilot, which reads nothing
else, picks its own split between a finger's joints: up to 0.3 rad (leap: 0.86) off the plan's
targets, with the fingertip pads turned differently (the Sharpa's distal joints end 0.2 rad less
flexed, and 2 of 12 canned-food grasps slip on lifting that hold with the plan's joint targets).
The other keypoints come from the parametric human hand (``streams/human_hand.py``) at the curl
whose tip is nearest, so every frame looks like a hand to anything that reads all 21 points.

Pinches: DexPilot reads a thumb tip within ``project_dist`` (3 cm, human scale) of a finger's as a
pinch and pulls the two robot tips together (weight 200). The scripted person pinches only where
the plan's pads meet (``project_dist`` 1 cm, escape 2 cm; the pad pinch's pads meet within 5 mm):
at 3 cm the pull also fired on grasps whose tips the plan keeps 6-30 mm apart (a power grasp's
fingers curled past the thumb, the pad pinch's folded fingers, the flat pinch's pads behind its
tips) and opened the fingers: the RH5DG2's power grasp 0.38 rad short of its 1.32 (its 1.2 kg bottle
slipped), the Revo2's flat pinch 0.24 rad off (its 5 mm pen lifted 3 cm instead of 14). With exact
fingertips and no stray pinch, DexPilot returns the plan's joints on every hand whose fingertips fix
them (tests/teleop/test_stream_closure.py). Two fingers pinching the thumb together are kept
``eta2`` = 3 cm apart in a live session, so that a person's tripod does not make robot fingers
collide; the plan's tripod pinch (all three pads towards one point inside the ball) then spread
its fingers and rolled the ping-pong ball away (ball_box_loading__ur5_wuji: 0/3, direct joint path
2/3). The scripted person's retargeter therefore lets them meet (3/3). Keeping the thumb out of the
pinch zone instead left it 36 mm from the index tip, too far to hold a golf ball.

Latency: DexPilot low-passes the keypoints and the joint targets (``retarget/filters.py``), which
a live operator feels as a constant lag and, with practice, moves ahead of. The scripted person
does so exactly: the hand pose it shows leads the plan by what the joint filter will take back
(``q + (1 - a) / a * dq``) and the keypoints it sends lead what the keypoint filter will take back,
so the filtered command lands on the plan instead of a step or two behind it. Left to lag, the
fingers were still on a placed bottle when the wrist retreated and tipped it over (2/12 successes
on condiment_box_loading__ur5_wuji, against 12/12 for the direct joint path).
"""

from __future__ import annotations

import mujoco
import numpy as np

from sim import physics
from sim.embodiment.description import Transform, quat_to_mat
from sim.scene.builder import Scene
from teleop.recorder import StreamStep, stream_settings
from teleop.retarget import DexPilotConfig, HandKinematics, TeleopCommander
from teleop.scripted_operator import ScriptedOperator
from teleop.streams import OperatorFrame, StreamSanitizer
from teleop.streams.frame import KP, SIDES
from teleop.streams.human_hand import (FINGERS, MIRROR, THUMB_CMC, THUMB_OPEN_DIR, THUMB_OPPOSED_DIR, finger_points,
                                       hand_keypoints)

from .session_driver import NS_PER_S, session_time_ns

NOMINAL_PERIOD_NS = NS_PER_S // physics.CONTROL_HZ      # one frame per control step
CURL_GRID = np.linspace(0.0, 1.0, 41)
OPPOSITION_GRID = np.linspace(0.0, 1.0, 21)
REACH_IK_ITERS = 30     # as the direct joint path: warm-started, the plan moves little per step
# DexPilot as in a live session, except that the scripted person pinches only where the plan's pads
# meet and two fingers pinching the thumb together may meet (eta2 is the thumb-finger distance): see
# "Pinches" above.
SCRIPTED_RETARGET = DexPilotConfig(eta2=DexPilotConfig().eta1, project_dist=0.01, escape_dist=0.02)
# The live session's pinch distances (3 cm, escape 5 cm), against which the plans were first tuned
LIVE_PINCH_RETARGET = DexPilotConfig(eta2=DexPilotConfig().eta1)


class RobotShapedHand:
    """Human keypoints (right hand, wrist frame) whose wrist-to-fingertip vectors, times the
    retarget scale, are the robot hand's at given actuator targets."""

    def __init__(self, kin: HandKinematics):
        self.kin = kin      # may be a retargeter's own: every call sets the whole configuration
        self.scale = self.kin.spec.scale
        self.tip_keypoints = np.array([KP[t.keypoint] for t in self.kin.spec.fingertips])
        self.fingers = [t.keypoint.removesuffix("_tip") for t in self.kin.spec.fingertips]
        # the human model's fingertip at each curl, to pick the knuckles that go with a tip
        self.curl_tips = {f: np.array([finger_points(f, c)[-1] for c in CURL_GRID]) for f in FINGERS}
        dirs = np.outer(1 - OPPOSITION_GRID, THUMB_OPEN_DIR) + np.outer(OPPOSITION_GRID, THUMB_OPPOSED_DIR)
        self.thumb_dirs = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)

    def keypoints(self, q: np.ndarray, side: str) -> np.ndarray:
        P = self.kin.points(q)
        tips = (P[1:] - P[0]) / self.scale
        curls = {}
        for finger, tip in zip(self.fingers, tips):
            if finger in self.curl_tips:
                curls[finger] = CURL_GRID[np.argmin(np.linalg.norm(self.curl_tips[finger] - tip, axis=1))]
        default = float(np.mean(list(curls.values()))) if curls else 0.0     # a finger the robot lacks
        thumb_tip = tips[self.fingers.index("thumb")]
        # the thumb's metacarpal leaves the CMC roughly towards the tip: the opposition whose
        # metacarpal direction is closest to the CMC-to-tip direction
        opposition = OPPOSITION_GRID[np.argmax(self.thumb_dirs @ (thumb_tip - THUMB_CMC))]
        kp = hand_keypoints([curls.get(f, default) for f in FINGERS], thumb_tip, opposition)
        kp[self.tip_keypoints] = tips        # exact: these are what DexPilot reads
        return kp * MIRROR if side == "left" else kp


class ScriptedStreamOperator:
    """The recorder's ``Operator``: the scripted plan, delivered as an operator stream. After each
    ``act`` the step's ``StepFlag`` bits and reasons are in ``step_flags`` / ``step_reasons``."""

    name = "scripted:stream"

    def __init__(self, retarget_config: DexPilotConfig = SCRIPTED_RETARGET):
        self.plan = ScriptedOperator()
        self.retarget_config = retarget_config
        self.sanitizer = StreamSanitizer(NOMINAL_PERIOD_NS)
        self.commander: TeleopCommander | None = None
        self._model: mujoco.MjModel | None = None
        self.step_flags, self.step_reasons = 0, ""
        self.last_intent: dict = {}
        self._shown: dict[str, np.ndarray] = {}     # per side: last hand pose shown (joint space)
        self._sent: dict[str, np.ndarray] = {}      # ... and the keypoints the filter should hold
        self._arm_q: dict[str, np.ndarray] = {}     # per side: the arm pose the person last saw

    def reset(self, scene: Scene, data: mujoco.MjData) -> None:
        self.plan.reset(scene, data)
        if scene.model is not self._model:
            self.commander = TeleopCommander(scene.model, scene.layout, retarget_config=self.retarget_config)
            self.hand = RobotShapedHand(self.commander.sides[SIDES[0]].retargeter.kin)
            self._model = scene.model
        self.commander.reset()
        self.sanitizer.reset()
        self._shown.clear()
        self._sent.clear()
        self.site_in_base_inv = {side: s.site_in_base.inverse() for side, s in self.commander.sides.items()}
        self._arm_q = {side: s.home_arm.copy() for side, s in self.commander.sides.items()}

    def frame(self, step: int, data: mujoco.MjData) -> OperatorFrame | None:
        """What the person's devices deliver at ``step``: both hands' keypoints and wrist poses."""
        self.last_intent = self.plan.intent(step, data)
        frame = OperatorFrame.empty(session_time_ns(step))
        for side, (pos, quat, hand_q) in self.last_intent.items():
            site = self._reachable(side, pos, quat)
            wrist = site @ self.site_in_base_inv[side]
            frame = frame.with_hand(side, self._lead(side, hand_q), wrist.pos, wrist.quat)
        return frame

    def _reachable(self, side: str, pos: np.ndarray, quat: np.ndarray) -> Transform:
        """The plan's wrist-site pose, or the pose closest to it that the arm reaches."""
        kin = self.commander.sides[side].kin
        result = kin.ik_tracking(pos, quat, self._arm_q[side], self.commander.sides[side].home_arm,
                                 max_iters=REACH_IK_ITERS)
        self._arm_q[side] = result.q
        if result.success:
            return Transform(np.asarray(pos, float), quat_to_mat(quat))
        T = kin.fk_se3(result.q)
        return Transform(T.translation.copy(), T.rotation.copy())

    def _lead(self, side: str, hand_q: np.ndarray) -> np.ndarray:
        """Keypoints that bring the filtered retargeting onto ``hand_q`` this step: each first-order
        filter ``y += a (x - y)`` is given ``x = y_prev + (y_want - y_prev) / a``. The first frame
        after reset passes the filters unchanged, so it is sent as it is."""
        cfg, kin = self.retarget_config, self.hand.kin
        prev_q, prev_kp = self._shown.get(side), self._sent.get(side)
        q = hand_q if prev_q is None else np.clip(prev_q + (hand_q - prev_q) / cfg.joint_alpha, kin.lower, kin.upper)
        want = self.hand.keypoints(q, side)
        self._shown[side], self._sent[side] = np.asarray(hand_q, float).copy(), want
        return want if prev_kp is None else prev_kp + (want - prev_kp) / cfg.keypoint_alpha

    @property
    def stream_settings(self) -> dict:
        """The recorder keeps the stream with these (``teleop/recorder.py``)."""
        return stream_settings(NOMINAL_PERIOD_NS, 1.0, self.retarget_config)

    def act(self, step: int, data: mujoco.MjData) -> np.ndarray:
        now = session_time_ns(step)
        self.stream_step = StreamStep(self.frame(step, data), now)
        cmd = self.commander.command(self.sanitizer.step(*self.stream_step))
        self.step_flags, self.step_reasons = int(cmd.flags), "\n".join(cmd.reasons)
        return cmd.ctrl

    def done(self, step: int) -> bool:
        return self.plan.done(step)
