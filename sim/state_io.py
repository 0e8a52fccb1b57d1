"""Exact MuJoCo state capture: the integration state (qpos, qvel, act, warm-start, ctrl, time...)
is everything `mj_step` depends on, so restoring it makes a re-simulation bit-identical."""

from __future__ import annotations

import mujoco
import numpy as np

STATE_SPEC = mujoco.mjtState.mjSTATE_INTEGRATION


def get_state(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    state = np.empty(mujoco.mj_stateSize(model, STATE_SPEC))
    mujoco.mj_getState(model, data, state, STATE_SPEC)
    return state


def set_state(model: mujoco.MjModel, data: mujoco.MjData, state: np.ndarray) -> None:
    expected = mujoco.mj_stateSize(model, STATE_SPEC)
    if state.shape != (expected,):
        raise ValueError(f"integration state has {state.shape[0]} values, the model needs {expected}")
    mujoco.mj_setState(model, data, state, STATE_SPEC)
