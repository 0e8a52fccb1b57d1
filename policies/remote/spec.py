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

import yaml

from policies.interface import ActionSpec, ObservationSpec
from sim.errors import SpecError


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
        if not isinstance(raw, dict):
            raise SpecError(where, "<document>", "a mapping with name, observation_spec, action_names, "
                                                 "actions_per_query", type(raw).__name__)
        for key in ("name", "observation_spec", "action_names", "actions_per_query"):
            if key not in raw:
                raise SpecError(where, key, "present (the remote policy's spec)")
        try:
            obs = ObservationSpec.from_dict(raw["observation_spec"])
        except TypeError as exc:
            raise SpecError(where, "observation_spec", f"the fields of an ObservationSpec ({exc})") from exc
        names = raw["action_names"]
        if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
            raise SpecError(where, "action_names", "a non-empty list of actuator names", names)
        per_query = raw["actions_per_query"]
        if not isinstance(per_query, int) or per_query < 1:
            raise SpecError(where, "actions_per_query", "an integer >= 1", per_query)
        return cls(str(raw["name"]), obs, ActionSpec(tuple(names)), per_query, raw.get("setting"),
                   [tuple(a) for a in raw.get("anchors") or []], raw.get("layout"))


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
