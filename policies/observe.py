"""What a policy sees, rendered online in the closed loop exactly as the render stage renders it offline
(the same camera rig and TacMap rig, posed from positions), so training and evaluation images agree.

MuJoCo's `mj_step` leaves body poses at the start of the step; the source poses the scene from the
current joint positions first (`mj_kinematics`, `mj_camlight`), as the render stage does from stored
states. The next `mj_step` recomputes everything, so this does not touch the physics.
"""

from __future__ import annotations

from collections import deque

import mujoco
import numpy as np

from policies.interface import ObservationSpec
from sim.registry import SensorProfile, parse_sensor_profile


def policy_profile(spec: ObservationSpec) -> SensorProfile:
    """A sensor profile that renders exactly the policy's inputs (RGB of its views, its TacMap grid)."""
    raw = {"name": "policy_inputs", "rate_hz": spec.rate_hz,
           "cameras": {"ids": list(spec.views), "width": spec.width, "height": spec.height, "modalities": ["rgb"],
                       **({"tessellation": list(spec.tessellation)} if spec.tessellation else {})},
           "tactile": {"enabled": bool(spec.tactile_sites), "resolution": 240, "step": spec.tactile_step,
                       "max_range_mm": 15.0}}
    return parse_sensor_profile(raw)


class ObservationSource:
    """Renders the policy's views (and TacMap sites) and keeps the last `n_obs_steps` frames."""

    def __init__(self, scene, spec: ObservationSpec):
        from sim.render import CameraRig

        self.scene, self.spec = scene, spec
        profile = policy_profile(spec)
        self.rig = CameraRig(scene.model, profile) if spec.views else None
        self.tactile = None
        if spec.tactile_sites:
            from tactile.rig import TactileRig
            self.tactile = TactileRig.for_profile(scene, profile)
            missing = set(spec.tactile_sites) - set(self.tactile.site_names)
            if missing:
                raise ValueError(f"tactile sites {sorted(missing)} not on this embodiment "
                                 f"({scene.layout.embodiment}: {list(self.tactile.site_names)})")
        self.history: deque[dict] = deque(maxlen=spec.n_obs_steps)
        self.seconds = {"render": 0.0}

    def capture(self, data: mujoco.MjData) -> None:
        """Render the current state into the history."""
        import time

        t0 = time.perf_counter()
        frame = {"state": data.qpos[self.scene.robot_qpos_adr].copy()}
        if self.rig is not None or self.tactile is not None:
            mujoco.mj_kinematics(self.scene.model, data)
            mujoco.mj_camlight(self.scene.model, data)
        if self.rig is not None:
            shots = self.rig.capture(data)
            frame["images"] = {v: shots[v]["rgb"] for v in self.spec.views}
        if self.tactile is not None:
            touch = self.tactile.capture(data)
            order = {s: i for i, s in enumerate(touch.site_names)}
            frame["tactile"] = {s: touch.tacmap[order[s]] for s in self.spec.tactile_sites}
        self.history.append(frame)
        self.seconds["render"] += time.perf_counter() - t0

    def observation(self, instruction: str, tick: int) -> dict:
        """The window of the last n_obs frames, oldest first; the oldest repeated until the history fills."""
        frames = list(self.history)
        frames = [frames[0]] * (self.spec.n_obs_steps - len(frames)) + frames
        obs = {"state": np.stack([f["state"] for f in frames]), "instruction": instruction, "tick": tick}
        if self.rig is not None:
            obs["images"] = {v: np.stack([f["images"][v] for f in frames]) for v in self.spec.views}
        if self.tactile is not None:
            obs["tactile"] = {s: np.stack([f["tactile"][s] for f in frames]) for s in self.spec.tactile_sites}
        return obs

    def close(self) -> None:
        # a rig dropped without close() and collected later corrupts other renderers' images
        if self.rig is not None:
            self.rig.close()
            self.rig = None
