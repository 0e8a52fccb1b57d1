"""Fixed-width action and state layouts for 32-dimensional heads (pi0.5 and GR00T N1.5 emit at most 32 action
dimensions; b2d's embodiments have 24-58 actuators and up to 70 joints).

A layout maps one embodiment's vector (actuator targets, or joint positions) to `dim` slots: the arm joints
are kept as they are, each hand's joints are reduced to its first k synergies (principal components of the
demonstrations' hand trajectories: x_hand ~ mean + basis^T z), and the rest is zero padding. A vector that
already fits is only padded. The mapping is data (YAML), computed from demonstrations by `compute_layout`,
with its reconstruction error over those demonstrations; the same file is applied on both sides of the
wire (the client encodes states and decodes actions, a b2d server the reverse).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from episodes.atomic import file_sha256, write_text_atomic
from sim.errors import SpecError, UnknownNameError

FORMAT = "b2d.layout/1"
HEAD_DIM = 32
LAYOUTS = Path(__file__).parent / "layouts"


@dataclass(frozen=True)
class Synergy:
    side: str
    names: tuple[str, ...]         # the hand's entries of the vector, in the vector's order
    mean: np.ndarray               # [n]
    basis: np.ndarray              # [k, n], orthonormal rows, largest-variance first


@dataclass(frozen=True)
class VectorLayout:
    """The mapping of one vector (actions or state) of `names` to `dim` slots."""

    names: tuple[str, ...]
    dim: int
    kept: tuple[str, ...]          # copied into the first slots, in this order
    synergies: tuple[Synergy, ...]

    @property
    def used(self) -> int:
        return len(self.kept) + sum(len(s.basis) for s in self.synergies)

    def slot_names(self) -> list[str]:
        slots = list(self.kept)
        for s in self.synergies:
            slots += [f"{s.side}_hand_synergy_{i}" for i in range(len(s.basis))]
        return slots + [f"pad_{i}" for i in range(self.dim - len(slots))]

    def _index(self, names) -> np.ndarray:
        order = {n: i for i, n in enumerate(self.names)}
        return np.array([order[n] for n in names], dtype=int)

    def encode(self, x: np.ndarray) -> np.ndarray:
        """[..., len(names)] -> [..., dim]."""
        x = np.asarray(x, dtype=np.float64)
        if x.shape[-1] != len(self.names):
            raise ValueError(f"layout encode: expected {len(self.names)} values per row, got {x.shape[-1]}")
        parts = [x[..., self._index(self.kept)]]
        for s in self.synergies:
            parts.append((x[..., self._index(s.names)] - s.mean) @ s.basis.T)
        out = np.concatenate(parts, axis=-1)
        pad = np.zeros(out.shape[:-1] + (self.dim - out.shape[-1],))
        return np.concatenate([out, pad], axis=-1)

    def decode(self, z: np.ndarray) -> np.ndarray:
        """[..., dim] -> [..., len(names)] (padding slots ignored)."""
        z = np.asarray(z, dtype=np.float64)
        if z.shape[-1] != self.dim:
            raise ValueError(f"layout decode: expected {self.dim} values per row, got {z.shape[-1]}")
        x = np.zeros(z.shape[:-1] + (len(self.names),))
        x[..., self._index(self.kept)] = z[..., : len(self.kept)]
        at = len(self.kept)
        for s in self.synergies:
            k = len(s.basis)
            x[..., self._index(s.names)] = s.mean + z[..., at: at + k] @ s.basis
            at += k
        return x


@dataclass(frozen=True)
class Layout:
    embodiment: str
    action: VectorLayout
    state: VectorLayout
    report: dict                   # reconstruction errors over the demonstrations, and their sources

    def to_dict(self) -> dict:
        def vec(v: VectorLayout) -> dict:
            return {"names": list(v.names), "kept": list(v.kept), "slots": v.slot_names(),
                    "synergies": [{"side": s.side, "names": list(s.names), "mean": s.mean.tolist(),
                                   "basis": s.basis.tolist()} for s in v.synergies]}
        return {"format": FORMAT, "embodiment": self.embodiment, "dim": self.action.dim,
                "action": vec(self.action), "state": vec(self.state), "report": self.report}

    @property
    def dim(self) -> int:
        return self.action.dim

    @property
    def content_hash(self) -> str:
        raw = {k: v for k, v in self.to_dict().items() if k != "report"}
        return hashlib.sha256(json.dumps(raw, sort_keys=True).encode()).hexdigest()[:12]

    @classmethod
    def from_dict(cls, raw, where: str | Path) -> "Layout":
        if not isinstance(raw, dict) or raw.get("format") != FORMAT:
            raise SpecError(where, "format", f"'{FORMAT}'", raw.get("format") if isinstance(raw, dict) else raw)
        dim = raw.get("dim")
        if not isinstance(dim, int) or dim < 1:
            raise SpecError(where, "dim", "an integer >= 1", dim)
        return cls(str(raw.get("embodiment")), _vector(raw.get("action"), dim, where, "action"),
                   _vector(raw.get("state"), dim, where, "state"), raw.get("report") or {})


def _vector(raw, dim: int, where, field: str) -> VectorLayout:
    if not isinstance(raw, dict):
        raise SpecError(where, field, "a mapping with names, kept, synergies")
    try:
        names, kept = tuple(raw["names"]), tuple(raw["kept"])
        synergies = []
        for i, s in enumerate(raw.get("synergies") or []):
            mean, basis = np.asarray(s["mean"], float), np.asarray(s["basis"], float).reshape(-1, len(s["names"]))
            if mean.shape != (len(s["names"]),):
                raise SpecError(where, f"{field}.synergies[{i}].mean", f"{len(s['names'])} values", mean.shape)
            synergies.append(Synergy(str(s["side"]), tuple(s["names"]), mean, basis))
    except (KeyError, TypeError, ValueError) as exc:
        raise SpecError(where, field, f"names, kept and synergies (side, names, mean, basis) ({exc})") from exc
    covered = list(kept) + [n for s in synergies for n in s.names]
    if sorted(covered) != sorted(names):
        raise SpecError(where, field, "kept and synergy names that together cover every name once",
                        sorted(set(names) ^ set(covered))[:6])
    vec = VectorLayout(names, dim, kept, tuple(synergies))
    if vec.used > dim:
        raise SpecError(where, field, f"at most {dim} slots", vec.used)
    return vec


def check_layout_fits(layout: Layout, spec, where: str) -> None:
    """A layout must map exactly the policy's actuators and joints, in their order."""
    if tuple(layout.action.names) != tuple(spec.action_spec.names):
        raise SpecError(where, "layout.action.names", f"the policy's {spec.action_spec.dim} actuators, in order "
                                                      f"(layout of {layout.embodiment})")
    if tuple(layout.state.names) != tuple(spec.observation_spec.state_names):
        raise SpecError(where, "layout.state.names", f"the policy's {len(spec.observation_spec.state_names)} "
                                                     f"joints, in order (layout of {layout.embodiment})")


def save_layout(layout: Layout, path: str | Path) -> Path:
    write_text_atomic(path, yaml.safe_dump(layout.to_dict(), sort_keys=False, width=120))
    return Path(path)


def load_layout(path: str | Path) -> Layout:
    path = Path(path)
    if not path.is_file():
        raise SpecError(path, "<file>", "a layout YAML file (b2d layout EPISODES... --out FILE)")
    try:
        raw = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, yaml.YAMLError) as exc:
        raise SpecError(path, "<document>", f"valid YAML ({exc})") from exc
    return Layout.from_dict(raw, path)


def embodiment_layout(embodiment: str) -> Layout:
    """The declared layout of an embodiment (policies/remote/layouts/<embodiment>.yaml)."""
    files = {p.stem: p for p in sorted(LAYOUTS.glob("*.yaml"))}
    if embodiment not in files:
        raise UnknownNameError("embodiment layout", embodiment, files)
    return load_layout(files[embodiment])


# ---------------------------------------------------------------- computing a layout from demonstrations


def _groups(embodiment: str, kind: str) -> tuple[list[str], list[tuple[str, list[str]]], list[str]]:
    """(vector names, [(side, hand names)], arm names) of an embodiment's actuators or joints."""
    import mujoco

    from sim.embodiment.builder import add_bimanual_robot

    robot = add_bimanual_robot(mujoco.MjSpec(), embodiment)
    if kind == "action":
        names = list(robot.actuator_names)
        hands = [(side, list(s.hand_actuators)) for side, s in robot.sides.items()]
        arms = [n for s in robot.sides.values() for n in s.arm_actuators]
    else:
        names = list(robot.joint_names)
        hands = [(side, list(s.hand_joints)) for side, s in robot.sides.items()]
        arms = [n for s in robot.sides.values() for n in s.arm_joints]
    return names, hands, arms


def _synergy(side: str, names: list[str], x: np.ndarray, k: int) -> tuple[Synergy, dict]:
    mean = x.mean(0)
    _, sing, vt = np.linalg.svd(x - mean, full_matrices=False)
    basis = vt[:k].copy()
    # SVD signs are arbitrary: fix each row's largest entry positive, so the file repeats run to run
    flip = np.sign(basis[np.arange(len(basis)), np.abs(basis).argmax(1)])
    basis *= np.where(flip == 0, 1.0, flip)[:, None]
    total = float((sing ** 2).sum())
    retained = float((sing[:k] ** 2).sum() / total) if total > 0 else 1.0
    return Synergy(side, tuple(names), mean, basis), {"side": side, "joints": len(names), "synergies": k,
                                                      "variance_retained": retained}


def _vector_layout(names, hands, arms, x: np.ndarray, dim: int) -> tuple[VectorLayout, dict]:
    if len(names) <= dim:                   # fits: identity plus padding
        return VectorLayout(tuple(names), dim, tuple(names), ()), {"reduced": False, "hands": []}
    budget = dim - len(arms)
    if budget < len(hands):
        raise ValueError(f"{len(arms)} arm entries leave no room for hand synergies in {dim} slots")
    col = {n: i for i, n in enumerate(names)}
    synergies, hand_report = [], []
    for i, (side, hand) in enumerate(hands):
        k = min(len(hand), budget // len(hands) + (1 if i < budget % len(hands) else 0))
        syn, rep = _synergy(side, hand, x[:, [col[n] for n in hand]], k)
        synergies.append(syn)
        hand_report.append(rep)
    vec = VectorLayout(tuple(names), dim, tuple(arms), tuple(synergies))
    return vec, {"reduced": True, "hands": hand_report}


def _errors(vec: VectorLayout, x: np.ndarray) -> dict:
    err = vec.decode(vec.encode(x)) - x
    return {"rms_rad": float(np.sqrt((err ** 2).mean())), "max_abs_rad": float(np.abs(err).max())}


def compute_layout(episodes: list[Path], dim: int = HEAD_DIM) -> Layout:
    """A layout from demonstrations (HDF5 episodes of one embodiment), with its reconstruction error on them."""
    from episodes.reader import EpisodeReader

    if not episodes:
        raise ValueError("no episodes to compute a layout from")
    actions, states, embodiment = [], [], None
    for path in sorted(Path(p) for p in episodes):
        with EpisodeReader(path) as r:
            emb = r.meta("embodiment")
            if embodiment not in (None, emb):
                raise SpecError(path, "meta.embodiment", f"'{embodiment}' like the other episodes", emb)
            embodiment = emb
            action_names, joint_names = list(r.static("action/names")), list(r.static("robot/joint_names"))
            actions.append(r.read("action/action").astype(np.float64))
            states.append(r.read("robot/qpos").astype(np.float64))
    report = {"episodes": [{"episode": p.name, "sha256": file_sha256(p)} for p in sorted(Path(e) for e in episodes)],
              "frames": int(sum(len(a) for a in actions))}
    vectors = {}
    for kind, x, stored in (("action", np.concatenate(actions), action_names),
                            ("state", np.concatenate(states), joint_names)):
        names, hands, arms = _groups(embodiment, kind)
        if names != stored:
            raise SpecError(episodes[0], f"{kind} names", f"the {kind} names of embodiment {embodiment}")
        vec, rep = _vector_layout(names, hands, arms, x, dim)
        vectors[kind] = vec
        report[kind] = {"entries": len(names), "slots_used": vec.used, **rep, **_errors(vec, x)}
    return Layout(embodiment, vectors["action"], vectors["state"], report)
