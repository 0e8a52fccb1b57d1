"""The scene's full position vector per frame, assembled from an episode by joint name.

Every joint of the model must come from the episode: robot joints from robot/qpos (columns named
by robot/joint_names), free objects from objects/{body}/pose_world (xyz + wxyz, MuJoCo's free-joint
layout), articulated-object joints ("<object>/<link>") from objects/{object}/qpos (columns named
by objects/{object}/joint_names). A joint with no source is an error naming the missing node.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from episode_media.source import FrameRange
from episodes.reader import EpisodeReader, open_episode
from sim.errors import SpecError

_FREE = int(mujoco.mjtJoint.mjJNT_FREE)
_SCALAR_JOINTS = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))


def episode_qpos(episode_file: str | Path | EpisodeReader, model: mujoco.MjModel,
                 frames: FrameRange | None = None) -> np.ndarray:
    """[T, nq] positions for the chosen frames (all frames by default) of `episode_file`."""
    if isinstance(episode_file, EpisodeReader):
        return _assemble(episode_file, model, frames)
    with open_episode(episode_file) as reader:
        return _assemble(reader, model, frames)


def _assemble(reader: EpisodeReader, model: mujoco.MjModel, frames: FrameRange | None) -> np.ndarray:
    num_frames = reader.num_frames
    frames = frames or FrameRange(0, num_frames)
    columns = _Columns(reader, num_frames, frames)
    qpos = np.empty((len(frames), model.nq))
    for j in range(model.njnt):
        name, kind, adr = model.joint(j).name, int(model.jnt_type[j]), int(model.jnt_qposadr[j])
        if name in columns.robot_names:
            qpos[:, adr] = columns.robot(name)
        elif kind == _FREE:
            qpos[:, adr: adr + 7] = columns.free_object(model.body(int(model.jnt_bodyid[j])).name)
        elif kind in _SCALAR_JOINTS and "/" in name:
            qpos[:, adr] = columns.articulated(name)
        else:
            raise SpecError(reader.path, "robot/joint_names",
                            f"joint '{name}' of the {model.nq}-position scene (not a robot joint, free object "
                            f"or '<object>/<link>' joint of an articulated object)")
    return qpos


class _Columns:
    """Reads each source dataset once, for the chosen frames only, checking its shape."""

    def __init__(self, reader: EpisodeReader, num_frames: int, frames: FrameRange):
        self.reader, self.num_frames, self.frames = reader, num_frames, frames
        self._cache: dict[str, np.ndarray] = {}
        self.robot_names = self._names("robot/joint_names")

    def _names(self, node: str) -> list[str]:
        if node not in self.reader:
            raise SpecError(self.reader.path, node, "a list of joint names")
        names = self.reader.static(node)
        if not isinstance(names, list):
            raise SpecError(self.reader.path, node, "a list of joint names", names)
        return names

    def _per_frame(self, node: str, width: int, what: str) -> np.ndarray:
        if node not in self._cache:
            if node not in self.reader:
                raise SpecError(self.reader.path, node, f"a float dataset [T, {width}] ({what})")
            values = self.reader.read(node)    # positions are small: read whole, check, then pick frames
            if values.shape != (self.num_frames, width) or values.dtype.kind != "f":
                raise SpecError(self.reader.path, node, f"a float dataset of shape ({self.num_frames}, {width}) "
                                                        f"({what})", f"{values.dtype} {values.shape}")
            f = self.frames
            self._cache[node] = values[f.start: f.stop: f.stride].astype(np.float64)
        return self._cache[node]

    def robot(self, joint: str) -> np.ndarray:
        block = self._per_frame("robot/qpos", len(self.robot_names), "robot joint positions, by robot/joint_names")
        return block[:, self.robot_names.index(joint)]

    def free_object(self, body: str) -> np.ndarray:
        return self._per_frame(f"objects/{body}/pose_world", 7, f"world pose of free object '{body}', xyz + wxyz")

    def articulated(self, joint: str) -> np.ndarray:
        obj = joint.split("/", 1)[0]
        names_node = f"objects/{obj}/joint_names"
        if names_node not in self.reader:
            raise SpecError(self.reader.path, names_node, f"the joint names of articulated object '{obj}' "
                                                          f"(the scene has joint '{joint}')")
        names = self._names(names_node)
        if joint not in names:
            raise SpecError(self.reader.path, names_node, f"an entry '{joint}' (a joint of the scene)", names)
        block = self._per_frame(f"objects/{obj}/qpos", len(names), f"joint positions of '{obj}', by {names_node}")
        return block[:, names.index(joint)]
