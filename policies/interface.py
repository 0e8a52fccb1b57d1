"""The one policy interface every policy implements: the privileged scripted baseline, ACT, Diffusion
Policy and remote policies.

A policy declares what it observes (`ObservationSpec`); the closed-loop runner (`policies/closed_loop.py`)
renders exactly that at the policy's rate and calls `act`, which returns an action chunk: rows of absolute
joint targets (one column per actuator), each held for one policy step. The runner executes
`actions_per_query` rows of a chunk, then queries again.

An observation (one query) is a dict:
- `images`: {view: uint8 [n_obs, H, W, 3]}, oldest first (the first frame repeated at the start)
- `state`: float64 [n_obs, J], the robot's active joint positions
- `tactile`: {site: uint8 [n_obs, Ht, Wt]} TacMap images, when the spec names sites
- `instruction`: the task's instruction; `tick`: the policy step index
- `sim`: (scene, MjData), only for a privileged policy (the scripted baseline reads the simulator)
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np


@dataclass(frozen=True)
class ObservationSpec:
    views: tuple[str, ...]
    width: int
    height: int
    rate_hz: int
    n_obs_steps: int = 1
    state_names: tuple[str, ...] = ()        # the robot joints whose positions the policy reads
    tactile_sites: tuple[str, ...] = ()
    tactile_shape: tuple[int, int] = (0, 0)
    tactile_step: int = 1                    # TacMap subsampling of the profile the policy was trained on
    privileged: bool = False                 # reads the simulator state (the scripted baseline only)
    tessellation: tuple[int, int] | None = None   # primitive (slices, stacks) of its views' renders

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, raw: dict) -> "ObservationSpec":
        tuples = {"views", "state_names", "tactile_sites", "tactile_shape", "tessellation"}
        return cls(**{k: tuple(v) if k in tuples and v is not None else v for k, v in raw.items()})


@dataclass(frozen=True)
class ActionSpec:
    names: tuple[str, ...]                   # actuator names, in the order of the action columns

    @property
    def dim(self) -> int:
        return len(self.names)


@runtime_checkable
class Policy(Protocol):
    name: str
    observation_spec: ObservationSpec
    action_spec: ActionSpec | None           # None: any embodiment (the scripted baseline)
    actions_per_query: int

    def reset(self, seed: int, instruction: str) -> None: ...
    def act(self, observation: dict) -> np.ndarray: ...


@dataclass
class PolicyError(Exception):
    """A policy that raised or returned a wrong shape: the runner ends that episode as an error."""

    message: str
    details: dict = field(default_factory=dict)

    def __str__(self) -> str:
        return self.message
