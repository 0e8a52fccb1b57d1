"""Simulation timing and solver options shared by every model b2d builds.

The paper's loop runs control and the evaluator at 60 Hz (one recorded action per step) and
cameras at 20 Hz. MuJoCo needs a finer integration step for stable finger contacts, so each
control step is split into SUBSTEPS physics steps.
"""

from __future__ import annotations

import mujoco

CONTROL_HZ = 60
SUBSTEPS = 8
TIMESTEP = 1.0 / (CONTROL_HZ * SUBSTEPS)
CONTROL_DT = 1.0 / CONTROL_HZ
HOMING_STEPS = 60  # control steps spent moving to the home pose before an episode (paper)


def configure_options(spec: mujoco.MjSpec) -> None:
    """Solver settings tuned for dexterous grasping: elliptic cones with a high impedance ratio
    keep finger contacts from slipping; implicitfast stays stable with stiff position servos."""
    spec.option.timestep = TIMESTEP
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.impratio = 10.0
    spec.option.noslip_iterations = 0
    spec.option.iterations = 50
    spec.option.ls_iterations = 20
    spec.compiler.autolimits = True


def step_control(model: mujoco.MjModel, data: mujoco.MjData, ctrl) -> None:
    """Hold `ctrl` (absolute joint targets) for one control step."""
    data.ctrl[:] = ctrl
    mujoco.mj_step(model, data, nstep=SUBSTEPS)
