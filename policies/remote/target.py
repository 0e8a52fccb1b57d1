"""What `b2d eval --remote URL` evaluates: the remote policy, its setting and its anchor scenes.

A b2d server names its checkpoint's setting and training scenes; for any other server the setting comes
from `--setting` and the spec from `--spec`, and the anchored channels (which start from recorded scenes)
need anchors that such a server cannot give, so only `inv_equi` runs unless the server provides them.
"""

from __future__ import annotations

from pathlib import Path

from policies.remote.client import RemotePolicy
from policies.remote.layout import load_layout
from policies.remote.spec import load_remote_spec
from sim import registry
from sim.scene.sample import SceneSample


def remote_target(url: str, spec_file: Path | None = None, setting: str | None = None,
                  layout_file: Path | None = None):
    """(policy, task, embodiment, anchors) for a remote policy server."""
    spec = load_remote_spec(spec_file) if spec_file else None
    layout = load_layout(layout_file) if layout_file else None
    policy = RemotePolicy(url, spec=spec, layout=layout)
    if setting:
        parsed = registry.parse_setting_key(setting)
        task, embodiment = parsed.task, parsed.embodiment
    elif policy.spec.setting:
        task, embodiment = policy.spec.setting["task"], policy.spec.setting["embodiment"]
    else:
        raise ValueError(f"policy server {url} names no setting: pass --setting <task>__<embodiment>")
    anchors = [(name, SceneSample.from_json(scene)) for name, scene in policy.spec.anchors]
    return policy, task, embodiment, anchors
