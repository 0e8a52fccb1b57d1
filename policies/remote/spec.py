"""What a client must know about a remote policy before the first episode: its observation spec (so the
closed loop renders the right views), its actuators, how many rows of a chunk to execute, and, when the
server serves a b2d checkpoint, the setting and the training scenes that anchor the evaluation channels.

A b2d server sends this itself (`get_spec` over TCP, the `b2d` entry of the websocket metadata); for any
other server (the official harness, an openpi server) the user declares it in a JSON or YAML file.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, ClassVar

import yaml

from pydantic import Field

from policies.interface import ActionSpec, ObservationSpec
from sim.errors import SpecError
from sim.schema import CatalogModel, validate
from sim.schema.base import Bool, Int, Name, PositiveInt, Str

Pair = Annotated[list[Int], Field(min_length=2, max_length=2)]


class ObservationSpecFields(CatalogModel):
    """`observation_spec`: what the policy observes (policies.interface.ObservationSpec)."""

    keys_label: ClassVar[str] = "an observation_spec key"

    views: list[Name] = Field(min_length=1)
    width: PositiveInt
    height: PositiveInt
    rate_hz: PositiveInt
    n_obs_steps: PositiveInt = 1
    state_names: list[Name] = []
    tactile_sites: list[Name] = []
    tactile_shape: Pair = [0, 0]
    tactile_step: PositiveInt = 1
    privileged: Bool = False
    tessellation: Pair | None = None


class SettingFields(CatalogModel):
    task: Name
    embodiment: Name


class RemoteSpecFields(CatalogModel):
    """A remote policy's spec, as a b2d server sends it or a user declares it for another server."""

    keys_label: ClassVar[str] = "a spec key"

    name: Str
    observation_spec: ObservationSpecFields
    action_names: list[Name] = Field(min_length=1, description="a non-empty list of actuator names")
    actions_per_query: PositiveInt
    setting: SettingFields | None = None
    anchors: list[Annotated[list[Str], Field(min_length=2, max_length=2)]] = []     # [episode, scene JSON]
    layout: dict | None = None                  # checked by policies/remote/layout.py


@dataclass(frozen=True)
class RemoteSpec:
    name: str
    observation_spec: ObservationSpec
    action_spec: ActionSpec
    actions_per_query: int
    setting: dict | None = None                         # {"task", "embodiment"}
    anchors: list = field(default_factory=list)         # [[episode name, scene sample JSON], ...]
    layout: dict | None = None                          # a fixed-width layout on the wire (policies/remote/layout.py)

    def to_dict(self) -> dict:
        return {"name": self.name, "observation_spec": self.observation_spec.to_dict(),
                "action_names": list(self.action_spec.names), "actions_per_query": self.actions_per_query,
                "setting": self.setting, "anchors": [list(a) for a in self.anchors], "layout": self.layout}

    @classmethod
    def from_dict(cls, raw, where: str | Path) -> "RemoteSpec":
        m = validate(RemoteSpecFields, raw, where)
        obs = ObservationSpec.from_dict(m.observation_spec.model_dump())
        return cls(m.name, obs, ActionSpec(tuple(m.action_names)), m.actions_per_query,
                   m.setting.model_dump() if m.setting is not None else None, [tuple(a) for a in m.anchors], m.layout)


def load_remote_spec(path: str | Path) -> RemoteSpec:
    """A declared spec, JSON or YAML (safe_load)."""
    path = Path(path)
    if not path.is_file():
        raise SpecError(path, "<file>", "a remote policy spec (JSON or YAML)")
    try:
        text = path.read_text(encoding="utf-8")
        raw = json.loads(text) if path.suffix == ".json" else yaml.safe_load(text)
    except (UnicodeDecodeError, json.JSONDecodeError, yaml.YAMLError) as exc:
        raise SpecError(path, "<document>", f"valid JSON or YAML ({exc})") from exc
    return RemoteSpec.from_dict(raw, path)


def checkpoint_spec(policy, layout: dict | None = None) -> RemoteSpec:
    """The spec of a b2d policy; a checkpoint's setting and training scenes when it has them."""
    ckpt = getattr(policy, "checkpoint", None)
    setting = anchors = None
    if ckpt is not None:
        setting = {"task": ckpt.task, "embodiment": ckpt.embodiment}
        anchors = [[Path(e["episode"]).stem, e["scene"]] for e in ckpt.manifest.get("training_set", [])
                   if e.get("scene")]
    return RemoteSpec(policy.name, policy.observation_spec, policy.action_spec, policy.actions_per_query,
                      setting, anchors or [], layout)
