"""Build and physics-speed figures for every embodiment (JSON-able, prints nothing).

    from sim.embodiment.bench import run_embodiment_bench
    figures = run_embodiment_bench()
"""

from __future__ import annotations

import time

import mujoco
import numpy as np

import sim.physics as physics

from .builder import add_bimanual_robot
from .description import embodiment_names


def _bench_one(name: str, control_steps: int) -> dict:
    t0 = time.perf_counter()
    spec = mujoco.MjSpec()
    physics.configure_options(spec)
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[3, 3, 0.1])
    layout = add_bimanual_robot(spec, name)
    t1 = time.perf_counter()
    model = spec.compile()
    t2 = time.perf_counter()
    data = mujoco.MjData(model)
    layout.apply_home(model, data)
    t3 = time.perf_counter()
    for _ in range(control_steps):
        physics.step_control(model, data, layout.home_ctrl)
    t4 = time.perf_counter()
    steps = control_steps * physics.SUBSTEPS
    sim_time = steps * model.opt.timestep
    return {
        "build_s": round(t1 - t0, 4), "compile_s": round(t2 - t1, 4),
        "nq": int(model.nq), "nv": int(model.nv), "nu": int(model.nu), "neq": int(model.neq),
        "nbody": int(model.nbody), "ngeom": int(model.ngeom),
        "physics_steps_per_s": round(steps / (t4 - t3), 1),
        "realtime_factor": round(sim_time / (t4 - t3), 2),
        "finite": bool(np.all(np.isfinite(data.qpos))),
    }


def run_embodiment_bench(control_steps: int = 300) -> dict:
    """Compile time, model sizes and physics steps per second (robot at rest at home, floor only)."""
    return {"control_steps": control_steps, "substeps": physics.SUBSTEPS,
            "embodiments": {name: _bench_one(name, control_steps) for name in embodiment_names()}}
