"""Checkpoints: a folder with the weights as safetensors and everything else as JSON; nothing is pickled.

    model.safetensors   weights (the EMA weights when the config keeps an EMA)
    policy.json         format, config, observation and action specs, setting, training set (files and
                        sha256), sensor profile hash, weights sha256, training summary
    stats.json          normalisation statistics (policies/normalize.py)
    train_log.json      the loss curve; loss.png its plot

The folder is written beside its final name and renamed into place. Loading checks the weights' sha256
(safetensors has no checksum of its own), so a flipped byte is a clear error, not a silently wrong policy.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from episodes.atomic import atomic_dir, file_sha256
from policies.config import PolicyConfig, parse_policy_config
from policies.interface import ActionSpec, ObservationSpec
from sim.errors import SpecError

FORMAT = "b2d.policy/1"
WEIGHTS, MANIFEST, STATS, TRAIN_LOG, LOSS_PLOT = ("model.safetensors", "policy.json", "stats.json",
                                                   "train_log.json", "loss.png")


@dataclass
class Checkpoint:
    path: Path
    config: PolicyConfig
    observation_spec: ObservationSpec
    action_spec: ActionSpec
    stats: dict
    manifest: dict
    state_dict: dict                  # name -> torch tensor

    @property
    def task(self) -> str:
        return self.manifest["setting"]["task"]

    @property
    def embodiment(self) -> str:
        return self.manifest["setting"]["embodiment"]


def save_checkpoint(out_dir: Path, state_dict: dict, config: PolicyConfig, observation_spec: ObservationSpec,
                    action_spec: ActionSpec, stats: dict, manifest: dict, train_log: list[dict]) -> Path:
    from safetensors.torch import save_file

    out_dir = Path(out_dir)
    with atomic_dir(out_dir, lambda p: (p / MANIFEST).is_file()) as tmp:
        tensors = {k: v.detach().cpu().contiguous() for k, v in state_dict.items()}
        save_file(tensors, str(tmp / WEIGHTS), metadata={"format": FORMAT})
        full = {"format": FORMAT, "policy": config.policy, "config_name": config.name,
                "config": config.model_dump(mode="json"), "config_hash": config.content_hash,
                "observation_spec": observation_spec.to_dict(), "action_names": list(action_spec.names),
                **manifest, "weights_sha256": file_sha256(tmp / WEIGHTS)}
        _write_json(tmp / MANIFEST, full)
        _write_json(tmp / STATS, stats)
        _write_json(tmp / TRAIN_LOG, train_log)
        plot_loss(train_log, tmp / LOSS_PLOT, title=f"{config.policy} {config.name}: "
                                                   f"{manifest.get('setting', {}).get('task', '')}")
    return out_dir


def _write_json(path: Path, value) -> None:
    path.write_text(json.dumps(value, indent=1, sort_keys=True) + "\n", encoding="utf-8")


def _read_json(path: Path) -> dict:
    if not path.is_file():
        raise SpecError(path, "<file>", "a checkpoint file (the folder is not a complete b2d checkpoint)")
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise SpecError(path, "<document>", f"valid JSON ({exc})") from exc


def load_checkpoint(path: str | Path) -> Checkpoint:
    from safetensors import SafetensorError
    from safetensors.torch import load_file

    path = Path(path)
    if not path.is_dir():
        raise SpecError(path, "<folder>", "a checkpoint folder (model.safetensors, policy.json, stats.json)")
    manifest = _read_json(path / MANIFEST)
    if manifest.get("format") != FORMAT:
        raise SpecError(path / MANIFEST, "format", f"'{FORMAT}'", manifest.get("format"))
    config = parse_policy_config(manifest.get("config", {}), path / MANIFEST)
    stats = _read_json(path / STATS)
    weights = path / WEIGHTS
    if not weights.is_file():
        raise SpecError(weights, "<file>", "the checkpoint's weights")
    if file_sha256(weights) != manifest.get("weights_sha256"):
        raise SpecError(weights, "<bytes>", f"sha256 {manifest.get('weights_sha256')} as policy.json records "
                                            "(the weights file is corrupt or was replaced)")
    try:
        state_dict = load_file(str(weights))
    except (SafetensorError, OSError, ValueError) as exc:
        raise SpecError(weights, "<file>", f"a readable safetensors file ({exc})") from exc
    try:
        spec = ObservationSpec.from_dict(manifest["observation_spec"])
        action = ActionSpec(tuple(manifest["action_names"]))
    except (KeyError, TypeError) as exc:
        raise SpecError(path / MANIFEST, "observation_spec / action_names", "the policy's specs") from exc
    _check_stats(path / STATS, stats, spec, action)
    return Checkpoint(path, config, spec, action, stats, manifest, state_dict)


def _check_stats(path: Path, stats: dict, spec: ObservationSpec, action: ActionSpec) -> None:
    """The statistics must describe the specs' joints, actions and views, or normalisation would misalign."""
    try:
        sizes = {"state": len(stats["state"]["mean"]), "action": len(stats["action"]["mean"])}
        views = set(stats["images"])
    except (KeyError, TypeError) as exc:
        raise SpecError(path, "state / action / images", "normalisation statistics of each") from exc
    if sizes["state"] != len(spec.state_names):
        raise SpecError(path, "state.mean", f"{len(spec.state_names)} values (the joints of policy.json)", sizes["state"])
    if sizes["action"] != action.dim:
        raise SpecError(path, "action.mean", f"{action.dim} values (the actuators of policy.json)", sizes["action"])
    if not set(spec.views) <= views:
        raise SpecError(path, "images", f"statistics of views {list(spec.views)}", sorted(views))


def plot_loss(train_log: list[dict], out: Path, title: str = "") -> None:
    """The training loss (and its parts) against the step, as a PNG."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.5), dpi=100)
    if train_log:
        steps = np.array([row["step"] for row in train_log])
        for key in sorted({k for row in train_log for k in row} - {"step", "lr", "seconds"}):
            ax.plot(steps, [row.get(key, np.nan) for row in train_log], label=key)
        ax.set_yscale("log")
        ax.legend()
    ax.set_xlabel("training step")
    ax.set_ylabel("loss")
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    # matplotlib stamps the PNG with its version only; no date, so the bytes repeat run to run
    fig.savefig(out, metadata={"Software": None})
    plt.close(fig)
