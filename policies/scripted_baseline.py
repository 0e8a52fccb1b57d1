"""The privileged scripted baseline: the scripted operator (the person the demonstrations come from)
behind the policy interface. It reads object poses from the simulator and looks at no image, so it is an
upper reference for the learned policies, not a policy that the invariance channels can disturb.
"""

from __future__ import annotations

import numpy as np

from policies.interface import ObservationSpec
from sim import physics

PRIVILEGED_SPEC = ObservationSpec(views=(), width=0, height=0, rate_hz=physics.CONTROL_HZ, privileged=True)


class ScriptedBaseline:
    name = "scripted_operator"
    observation_spec = PRIVILEGED_SPEC
    action_spec = None                  # drives any embodiment
    actions_per_query = 1

    def __init__(self, operator: str | None = None):
        from teleop.demos import DEFAULT_OPERATOR, OPERATORS

        operator = operator or DEFAULT_OPERATOR
        if operator not in OPERATORS:
            raise ValueError(f"operator: expected one of {list(OPERATORS)}, got {operator!r}")
        self.operator_name = operator
        self._make = OPERATORS[operator]
        self.operator = None

    def reset(self, seed: int, instruction: str) -> None:
        self.operator = self._make()
        self._started = False

    def act(self, observation: dict) -> np.ndarray:
        scene, data = observation["sim"]
        if not self._started:                 # the operator plans from the homed scene
            self.operator.reset(scene, data)
            self._started = True
        return np.asarray(self.operator.act(observation["tick"], data))[None]

    def done(self, tick: int) -> bool:
        return self._started and self.operator.done(tick)

    @property
    def step_flags(self) -> int:
        return getattr(self.operator, "step_flags", 0)

    @property
    def step_reasons(self) -> str:
        return getattr(self.operator, "step_reasons", "")
